"""`skinsuction design` against what happens: predictions vs FE virtual experiments diagnosed.

    python benchmarks/design_check.py [--skins 12] [--seed 0] [--workers 2]
        [--designs 2@100 2+6@100 2+4+8@100] [--given t_d=0.1]
        [--causes pre_tension hypodermis_thickness strain_stiffening]

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
    args = ap.parse_args(argv)

    given = {k.strip(): float(v) for k, _, v in (g.partition("=") for g in args.given)}
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


if __name__ == "__main__":
    sys.exit(main())
