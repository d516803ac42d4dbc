"""`skinsuction design` against what happens: predictions vs FE virtual experiments diagnosed.

    python benchmarks/design_check.py [--skins 12] [--seed 0] [--workers 2]
        [--designs 2@100 2+6@100 2+4+8@100]

Skins are drawn from the default box (X1d 0.007-0.09 MPa, X1h/X1d 0.003-0.3, 1 mm
layers; each cause's parameter drawn as `design` draws it). For each skin and
design, `design` predicts (from the spaces, noise-free: intervals, detectability,
attribution ceilings); then the same skin is measured: FE curves (reference mesh,
fallback meshes where the first solve stops; independent of the spaces' rays) of
the neo-Hookean skin and of the skin with each cause added, 2 µm noise, rounded
to the 0.01 mm reading step, and `diagnose` run on each (noise estimated from the
curves, as a user runs it). Prints per design, predicted against realised:

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
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd
from _pool import run_rows

CAUSES = ("pre_tension", "hypodermis_thickness", "strain_stiffening")
NOISE_UM, READING_MM = 2.0, 0.01


def _design(text):
    from skinsuction.design import designs_from

    probes, _, mbar = text.partition("@")
    return designs_from([probes], [float(mbar or 100)], noise_um=NOISE_UM,
                        resolution_mm=READING_MM)[0]


def _measure(skin, design, cause, seed, folder):
    """FE curves of the skin (with ``cause`` added), noisy, read at 0.01 mm: a CSV."""
    from skinsuction.design import CAUSE_COLUMNS
    from skinsuction.evaluation import virtual_experiment, write_csv
    from skinsuction.space import default_registry

    x1d = float(skin["x1d_mpa"])
    c = default_registry()[cause] if cause else None
    value = None if c is None else c.value(float(skin[CAUSE_COLUMNS[cause]]), x1d)
    ve = virtual_experiment(x1d, x1d * float(skin["x1h_ratio"]), c, value, noise_um=NOISE_UM,
                            seed=seed, probes_mm=design.probes_mm,
                            pressures_mbar=np.linspace(0, design.max_mbar, design.points),
                            fallback=[{"element": "quad9", "quadrature": "full",
                                       "wall_penalty": 1.0, "iterations_per_step": 30}])
    if not ve.converged:
        return None
    ve.curves = {k: np.round(m / READING_MM) * READING_MM for k, m in ve.curves.items()}
    return write_csv(ve, Path(folder) / f"{cause or 'none'}_{seed}.csv")


def _run(job):
    from skinsuction.design import predict_skin, relative_halfwidth
    from skinsuction.diagnose import Settings, diagnose_file
    from skinsuction.space import SHIPPED_SPACE_DIR, pairs_for, read_ray_spaces

    skin, text, seed = job
    design = _design(text)
    spaces = read_ray_spaces(SHIPPED_SPACE_DIR)
    settings = Settings(seed=seed)
    row = {"design": design.name, "skin": int(skin["skin"]), **skin}
    t0 = time.process_time()
    pred = predict_skin(skin, design, spaces, settings, causes=CAUSES)
    row["predict_cpu_s"] = time.process_time() - t0
    row.update({f"pred_{k}": v for k, v in pred.items() if k not in ("design", "skin")})
    pairs = pairs_for(None, spaces["neo_hookean"].spec)
    with tempfile.TemporaryDirectory() as folder:
        for cause in (None, *CAUSES):
            name = cause or "none"
            path = _measure(skin, design, cause, seed, folder)
            if path is None:
                row[f"real_{name}_error"] = "FE curve stopped"
                continue
            t0 = time.process_time()
            try:
                r = diagnose_file(path, None, settings, spaces=spaces, pairs=pairs,
                                  on_demand=False)
            except Exception as err:
                row[f"real_{name}_error"] = f"{type(err).__name__}: {err}"
                continue
            row[f"real_{name}_cpu_s"] = time.process_time() - t0
            row[f"real_{name}_verdict"] = r["verdict"]
            row[f"real_{name}_cause"] = r["cause"]
            row[f"real_{name}_tied"] = ";".join(r["ambiguous_with"] or [])
            if cause is None:
                truth = {"X1d": float(skin["x1d_mpa"]),
                         "X1h": float(skin["x1d_mpa"] * skin["x1h_ratio"])}
                for k, v in truth.items():
                    iv = (r["baseline"]["intervals"] or {}).get(k)
                    ns = None if iv is None else argparse.Namespace(**iv)
                    est = r["baseline"]["parameters"][k]
                    row[f"real_{k}_halfwidth"], row[f"real_{k}_bounded"] = (
                        relative_halfwidth(k, est, ns))
                    row[f"real_{k}_covers"] = (None if ns is None
                                               else bool(ns.lower <= v <= ns.upper))
    return row


def _binom(p, n):
    return math.sqrt(max(p * (1 - p), 1e-12) / max(n, 1))


def summary(df: pd.DataFrame) -> list:
    from skinsuction.evaluation import attribution_ceiling

    lines = []
    for design, g in df.groupby("design", sort=False):
        ok = g[~g["pred_beyond_space"].fillna(False).astype(bool)]
        lines.append(f"{design}: {len(g)} skins, {len(g) - len(ok)} beyond the space")
        for k in ("X1d", "X1h"):
            pw = ok[f"pred_{k}_halfwidth"].astype(float)
            rw = ok[f"real_{k}_halfwidth"].astype(float)
            pb = ok[f"pred_{k}_bounded"].fillna(False).astype(bool).mean()
            rb = ok[f"real_{k}_bounded"].fillna(False).astype(bool).mean()
            cov = ok[f"real_{k}_covers"].dropna().astype(bool)
            lines.append(f"  {k}: half-width median predicted {100 * pw.median():.3g} %, "
                         f"realised {100 * rw.median():.3g} %; bounded predicted {pb:.2f}, "
                         f"realised {rb:.2f} (binomial sd {_binom(pb, len(ok)):.2f}); "
                         f"realised intervals cover the truth in {cov.sum()}/{len(cov)}")
        for c in CAUSES:
            det = ok[f"pred_{c}_detectable"]
            found = ok[f"real_{c}_verdict"] == "cause_found"
            pdet = det.fillna(False).astype(bool)
            lines.append(f"  {c}: detectable predicted {pdet.mean():.2f}, a cause found "
                         f"realised {found.mean():.2f} (sd {_binom(pdet.mean(), len(ok)):.2f})")
            on = ok[pdet]
            if len(on):
                gaps = on[[col for col in on if col.startswith(f"pred_{c}_vs_")]]
                ceiling = attribution_ceiling(gaps.min(axis=1).astype(float)).mean()
                named = on[f"real_{c}_cause"] == c
                tied = on[f"real_{c}_tied"].fillna("").astype(str).str.len() > 0
                lines.append(f"    over the {len(on)} predicted detectable: ceiling "
                             f"{ceiling:.2f}, named right {named.mean():.2f} "
                             f"(sd {_binom(ceiling, len(on)):.2f}); right or tied "
                             f"{(named | tied).mean():.2f}, wrong and not tied "
                             f"{(~named & ~tied).mean():.2f}")
    return lines


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--skins", type=int, default=12)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--designs", nargs="+", default=["2@100", "2+6@100", "2+4+8@100"])
    ap.add_argument("--out", default="benchmarks/out/design_check.csv")
    args = ap.parse_args(argv)

    from skinsuction.design import Box

    skins = Box().draw(args.skins, args.seed)
    jobs = [(r._asdict(), d, args.seed + 100 * i + j) for j, d in enumerate(args.designs)
            for i, r in enumerate(skins.itertuples(index=False))]
    df, seconds = run_rows(_run, jobs, args.workers, args.out)
    out = Path(args.out)
    print(f"{args.skins} skins x {len(args.designs)} designs, {seconds:.0f} s "
          f"wall on {args.workers} workers; 2 µm noise, 0.01 mm reading")
    print("\n".join(summary(df)))
    print(f"written: {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
