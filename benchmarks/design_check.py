"""`skinsuction design` against what happens: predictions vs FE virtual experiments diagnosed.

    python benchmarks/design_check.py [--skins 12] [--seed 0] [--workers 2]
        [--designs 2@100 2+6@100 2+4+8@100] [--given t_d=0.1]
        [--causes pre_tension hypodermis_thickness strain_stiffening]
    python benchmarks/design_check.py --repredict results/design/check/rows.csv [--workers 1]

Skins are drawn from the default box (X1d 0.007-0.09 MPa, X1h/X1d 0.003-0.3, 1 mm
layers; each cause's parameter drawn as `design` draws it). For each skin and
design, `design` predicts (from the spaces, noise-free: intervals, detectability,
attribution ceilings); then the same skin is measured: FE curves (reference mesh,
fallback meshes where the first solve stops; independent of the spaces' rays) of
the neo-Hookean skin and of the skin with each cause added, 2 µm noise, rounded
to the 0.01 mm reading step, and `diagnose` run on each (noise estimated from the
curves, as a user runs it). `--given t_d=0.1` writes the dermis thickness (its true
value) and that sd in each file's header, as an ultrasound measurement is given, and
predicts with it given. Prints per design, predicted against realised:

* the median 95 % half-width of X1d and X1h (the realised one: the diagnosis's
  neo-Hookean intervals) and the fraction of skins bounded (with the binomial sd);
* per cause, the detectable fraction against the fraction where the diagnosis
  found a cause, and the mean attribution ceiling (against the nearest of every
  cause the diagnosis weighs) against the fraction named right, over the skins
  predicted detectable; also right or tied, and wrong and not tied.

`--repredict ROWS.csv` makes the predictions of an earlier check's rows again (its
designs, skins and given thicknesses) and keeps their FE measurements and diagnoses:
for a change of the prediction alone, without the hours of FE runs.

Asserts nothing; writes every row to benchmarks/out/design_check.csv.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from _pool import run_rows

NOISE_UM, READING_MM = 2.0, 0.01


def _run(job):
    from skinsuction.design import check_skin, parse_design
    from skinsuction.diagnose import Settings
    from skinsuction.space import SHIPPED_SPACE_DIR, pairs_for, read_ray_spaces

    skin, text, seed, given, causes = job
    design = parse_design(text, noise_um=NOISE_UM, resolution_mm=READING_MM, given=given)
    spaces = read_ray_spaces(SHIPPED_SPACE_DIR)
    return check_skin(skin, design, seed, spaces, Settings(seed=seed), causes=causes,
                      pairs=pairs_for(None, spaces["neo_hookean"].spec),
                      on_demand=None if given else False)


def _repredict(job):
    from skinsuction.design import parse_design, repredict
    from skinsuction.diagnose import Settings
    from skinsuction.space import SHIPPED_SPACE_DIR, read_ray_spaces

    row, text, given, causes = job
    design = parse_design(text, noise_um=NOISE_UM, resolution_mm=READING_MM, given=given)
    spaces = read_ray_spaces(SHIPPED_SPACE_DIR)
    return repredict(row, design, spaces, Settings(seed=int(row["seed"])), causes=causes,
                     on_demand=None if given else False)


def _given_of(name: str, sd: dict) -> dict:
    """The given thicknesses of a design's name ("..., t_d given"), with their sd
    (``--given``: a name does not carry it)."""
    keys = [k for k in ("t_d", "t_h") if f"{k} given" in name]
    missing = [k for k in keys if k not in sd]
    if missing:
        raise SystemExit(f"design {name!r} gives {', '.join(missing)}: pass its sd with "
                         f"--given {missing[0]}=SD (as the check was run)")
    return {k: sd[k] for k in keys}


def main(argv=None):
    from skinsuction.design import CHECK_CAUSES, Box, check_summary

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--skins", type=int, default=12)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--designs", nargs="+", default=["2@100", "2+6@100", "2+4+8@100"])
    ap.add_argument("--given", nargs="*", default=[], metavar="KEY=SD",
                    help="thicknesses given with their sd (mm), e.g. t_d=0.1")
    ap.add_argument("--causes", nargs="+", default=list(CHECK_CAUSES))
    ap.add_argument("--out", default="benchmarks/out/design_check.csv")
    ap.add_argument("--repredict", metavar="ROWS.csv",
                    help="predict an earlier check's rows again, keeping its measurements")
    args = ap.parse_args(argv)

    given = {k.strip(): float(v) for k, _, v in (g.partition("=") for g in args.given)}
    if args.repredict:
        import pandas as pd

        old = pd.read_csv(args.repredict)
        jobs = [(r, _design_text(r["design"]), _given_of(r["design"], given or {}),
                 tuple(args.causes)) for r in old.to_dict("records")]
        df, seconds = run_rows(_repredict, jobs, args.workers, args.out)
        print(f"{len(df)} rows of {args.repredict} predicted again, {seconds:.0f} s wall on "
              f"{args.workers} workers; their FE measurements and diagnoses kept")
        print("\n".join(check_summary(df, args.causes)))
        print(f"written: {Path(args.out)}")
        return 0
    skins = Box().draw(args.skins, args.seed)
    jobs = [(r._asdict(), d, args.seed + 100 * i + j, given, tuple(args.causes))
            for j, d in enumerate(args.designs) for i, r in enumerate(skins.itertuples(index=False))]
    df, seconds = run_rows(_run, jobs, args.workers, args.out)
    print(f"{args.skins} skins x {len(args.designs)} designs, {seconds:.0f} s "
          f"wall on {args.workers} workers; 2 µm noise, 0.01 mm reading"
          + (f"; given {given}" if given else ""))
    print("\n".join(check_summary(df, args.causes)))
    print(f"written: {Path(args.out)}")
    return 0


def _design_text(name: str) -> str:
    """A design's name ("2+4+8 mm, 300 mbar, t_d given") -> its text ("2+4+8@300")."""
    probes, _, rest = name.partition(" mm, ")
    return f"{probes}@{rest.partition(' mbar')[0]}"


if __name__ == "__main__":
    sys.exit(main())
