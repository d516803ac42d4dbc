"""Confusion matrix of `skinsuction diagnose` over many seeded virtual experiments.

For each true cause (none and every cause of the ray spaces) ``--per-cause``
virtual experiments are drawn from seeds (moduli, effect size and noise in the
detectable ranges of skinsuction.diagnose.DRAW_RANGES and DETECTABLE_EFFECTS),
made by direct FE runs on the mesh of the spaces (both probes, 51 pressures,
Gaussian noise), written as measured CSV files and diagnosed with the default
settings.  Prints the confusion matrix (rows: truth, columns: named cause), the
rate at which each true cause is named, the false-alarm rate on `none`, how
often the tie with another cause was reported, the errors of the extended
parameters and the run time of one diagnosis; writes every draw to --out.

    python benchmarks/diagnose_confusion.py --space-dir results/diagnosis/spaces \\
        [--per-cause 40] [--workers 2] [--out results/benchmarks/diagnose_confusion.csv]

It takes minutes to an hour (2 FE runs and one diagnosis per draw).
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

_SPACES = None


def _spaces(space_dir):
    global _SPACES
    if _SPACES is None:
        from skinsuction.diagnose import read_ray_spaces

        _SPACES = read_ray_spaces(space_dir)
    return _SPACES


def one_draw(job):
    """Draw, simulate, diagnose one virtual experiment; a row of the results."""
    from skinsuction.diagnose import Settings, diagnose_file, draw_experiment, write_csv

    truth, seed, space_dir, mesh, settings = job
    spaces = _spaces(space_dir)
    cause = None if truth == "none" else spaces[truth].cause
    t0 = time.perf_counter()
    ve = draw_experiment(seed, cause, mesh=mesh)
    t_fe = time.perf_counter() - t0
    row = {"truth": truth, "seed": seed, "x1d": ve.x1d, "x1h": ve.x1h,
           "ratio": ve.x1h / ve.x1d, "noise_um": ve.noise_um, "value": ve.value,
           "fe_converged": ve.converged, "fe_seconds": t_fe}
    if not ve.converged:
        row["named"] = "fe_failed"
        return row
    with tempfile.TemporaryDirectory() as d:
        csv = write_csv(ve, Path(d) / "v.csv")
        t0 = time.perf_counter()
        rep = diagnose_file(csv, space_dir, Settings(**settings), spaces=spaces)
        row["diagnose_seconds"] = time.perf_counter() - t0
        row["diagnose_cpu_seconds"] = rep["cpu_seconds"]
    row.update(named=rep["cause"], verdict=rep["verdict"],
               ambiguous_with=";".join(rep.get("ambiguous_with") or []),
               noise_est_um=rep["noise_um"],
               base_misfit=rep["baseline"]["systematic_misfit"],
               base_p=rep["baseline"]["misfit_test"]["p_value"],
               base_x1d=rep["baseline"]["parameters"]["X1d"])
    for c in rep["candidates"]:
        row[f"dbic_{c['cause']}"] = c["delta_bic"]
        row[f"removes_{c['cause']}"] = c["removes_misfit"]
        row[f"holdout_ratio_{c['cause']}"] = c["holdout_ratio"]
    if rep["extended"]:
        p = rep["extended"]["parameters"]
        row["ext_x1d"] = p["X1d"]
        row["ext_x1h"] = p["X1h"]
        sym = spaces[rep["cause"]].cause.symbol
        row["ext_value"] = p[sym]
        row["E_ratio"] = rep["gain"]["E_ratio"]
        row["delta_bic"] = rep["gain"]["delta_bic"]
    return row


def confusion(rows: pd.DataFrame, causes) -> pd.DataFrame:
    labels = ["none", *causes]
    cols = labels + sorted(set(rows["named"]) - set(labels))
    m = pd.crosstab(rows["truth"], rows["named"]).reindex(index=labels, columns=cols,
                                                           fill_value=0)
    return m


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--space-dir", default="results/diagnosis/spaces")
    ap.add_argument("--per-cause", type=int, default=40)
    ap.add_argument("--seed", type=int, default=1000, help="first seed (default 1000)")
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--out", default="results/benchmarks/diagnose_confusion.csv")
    ap.add_argument("--repeats", type=int, default=None,
                    help="window focusing runs per fit (default: the package default)")
    args = ap.parse_args(argv)

    spaces = _spaces(args.space_dir)
    causes = [n for n in spaces if n != "neo_hookean"]
    mesh = spaces["neo_hookean"].spec.mesh
    settings = {} if args.repeats is None else {"repeats": args.repeats}
    jobs = [(truth, args.seed + 100000 * k + i, args.space_dir, mesh, settings)
            for k, truth in enumerate(["none", *causes]) for i in range(args.per_cause)]
    print(f"{len(jobs)} virtual experiments ({args.per_cause} per true cause), spaces "
          f"{args.space_dir} (mesh {mesh}), {args.workers} worker(s)", flush=True)
    t0 = time.perf_counter()
    rows = []
    if args.workers > 1:
        from concurrent.futures import ProcessPoolExecutor

        with ProcessPoolExecutor(args.workers) as pool:
            for i, row in enumerate(pool.map(one_draw, jobs), 1):
                rows.append(row)
                if i % 10 == 0:
                    print(f"  {i}/{len(jobs)} ({time.perf_counter() - t0:.0f} s)", flush=True)
    else:
        for i, job in enumerate(jobs, 1):
            rows.append(one_draw(job))
            if i % 10 == 0:
                print(f"  {i}/{len(jobs)} ({time.perf_counter() - t0:.0f} s)", flush=True)
    df = pd.DataFrame(rows)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    df.to_csv(out, index=False)

    ok = df[df["named"] != "fe_failed"]
    m = confusion(ok, causes)
    print("\nConfusion matrix (rows: true cause, columns: cause named by diagnose)")
    print(m.to_string())
    print("\nRate at which the true cause is named:")
    for truth in m.index:
        n = int(m.loc[truth].sum())
        k = int(m.loc[truth, truth]) if truth in m.columns else 0
        amb = ok[(ok["truth"] == truth) & (ok["ambiguous_with"].fillna("") != "")]
        print(f"  {truth:18s} {k:3d}/{n:<3d} = {k / max(n, 1):5.1%}"
              f"   (a tie with another cause reported in {len(amb)})")
    none = ok[ok["truth"] == "none"]
    fa = float((none["named"] != "none").mean()) if len(none) else float("nan")
    mis = float(none["base_misfit"].mean()) if len(none) else float("nan")
    print(f"\nFalse-alarm rate on none: {fa:.1%} (a cause named); baseline misfit flagged "
          f"in {mis:.1%}")
    hit = ok[(ok["truth"] == ok["named"]) & (ok["truth"] != "none")]
    if len(hit):
        print("\nErrors of the extended parameters where the cause was named:")
        for truth, g in hit.groupby("truth"):
            x1d = (g["ext_x1d"] / g["x1d"] - 1).abs()
            if spaces[truth].cause.modulus:
                v = (g["ext_value"] / g["value"] - 1).abs()
                vtxt = f"relative |error| median {v.median():.1%}, max {v.max():.1%}"
            else:
                v = (g["ext_value"] - g["value"]).abs()
                vtxt = f"|error| median {v.median():.3g}, max {v.max():.3g}"
            print(f"  {truth:18s} X1d relative |error| median {x1d.median():.1%}, "
                  f"max {x1d.max():.1%}; {spaces[truth].cause.symbol} {vtxt}; "
                  f"E ratio median {g['E_ratio'].median():.2f}")
    print(f"\nOne diagnosis: median {ok['diagnose_seconds'].median():.1f} s wall, "
          f"{ok['diagnose_cpu_seconds'].median():.1f} s CPU, max "
          f"{ok['diagnose_seconds'].max():.1f} s wall (FE of one virtual experiment: median "
          f"{df['fe_seconds'].median():.1f} s); FE failures {int((df['named'] == 'fe_failed').sum())}")
    print(f"total {time.perf_counter() - t0:.0f} s; rows written to {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
