"""How far other discretisations and FE codes are from the space's own FE curves.

The draws of the confusion benchmark (``benchmarks/diagnose_confusion.py``: the
physiological domain, each cause, the 2 + 6 and 4 + 8 mm probes, seeds ``--seed +
100000 k + i``) are solved noise-free by the space's own discretisation and by each
solver of ``skinsuction.evaluation.OTHER_SOLVERS`` asked for (a refined mesh, quad9
cells, FElupe's assembly, CalculiX).  Prints, per solver, probe and load band
(q = p / X1d, mbar/MPa), the rms and 95th percentile of the relative difference
M_solver / M_space - 1, and of the difference in µm; writes every point to ``--out``.
The curves go to the confusion benchmark's cache (``--cache``), so that its runs with
``--solver`` diagnose the same curves without solving them again.  Asserts nothing.

    python benchmarks/discretisation_error.py [--per-cause 20] [--solvers refined quad9] \\
        [--calculix-per-cause 8] [--out benchmarks/out/discretisation_error.csv]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

#: load bands (mbar/MPa) of the printed table: those of the space's error profile
BANDS = (0.0, 1500.0, 5500.0, 12000.0, 20000.0, 71500.0)


def _cpu() -> float:
    """CPU seconds of this process and its finished children (CalculiX runs as one)."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def curves_of(job):
    """The noise-free curves of one draw under each solver (from the cache or solved)."""
    from skinsuction.evaluation import SolverRefused, draw_wide, solver_curves
    from skinsuction.evaluation._confusion import (_cached_clean, _draw_keywords,
                                                   _save_clean)
    from skinsuction.evaluation._solvers import solver_mesh
    from skinsuction.space import read_ray_spaces

    truth, seed, space_dir, solvers, cache = job
    spaces = read_ray_spaces(space_dir)
    base = spaces["neo_hookean"]
    cause = None if truth == "none" else spaces[truth].cause
    d = draw_wide(seed, cause, None, base.spec.load_max)
    p = np.arange(0.0, d["p_max"] + 1e-9, d["p_step"])
    rows = []
    curves = {}
    for solver in ("space", *solvers):
        mesh = solver_mesh(solver, base.spec.mesh)
        path, clean = _cached_clean(cache, truth, seed, d, mesh, solver)
        t0 = _cpu()
        if clean is None:
            try:
                clean = solver_curves(solver, _draw_keywords(d, cause, base.spec.bottom),
                                      d["probes"], p, base.spec.mesh, list(base.spec.fallback))
            except SolverRefused:
                continue
            if path is not None:
                _save_clean(path, d, mesh, clean, solver)
        curves[solver] = (clean, _cpu() - t0)
    ref = curves.get("space", (None,))[0]
    for solver, (clean, cpu) in curves.items():
        if solver == "space":
            continue
        for probe, m in clean.items():
            m0 = np.asarray(ref[float(probe)], dtype=float)
            m = np.asarray(m, dtype=float)
            ok = (p > 0) & np.isfinite(m) & np.isfinite(m0)
            rows += [{"truth": truth, "seed": seed, "solver": solver, "probe": float(probe),
                      "x1d": d["x1d"], "ratio": d["ratio"], "value": d["value"],
                      "pressure": float(pi), "load": float(pi / d["x1d"]), "m_space": float(a),
                      "m_solver": float(b), "rel": float(b / a - 1), "diff_um": 1e3 * (b - a),
                      "cpu_seconds": cpu}
                     for pi, a, b in zip(p[ok], m0[ok], m[ok])]
    return rows


def table(df: pd.DataFrame) -> pd.DataFrame:
    band = pd.cut(df["load"], BANDS, include_lowest=True)
    g = df.groupby(["solver", "probe", band], observed=True)
    return pd.DataFrame({
        "points": g.size(),
        "draws": g["seed"].nunique(),
        "rms_rel_%": g["rel"].apply(lambda r: 100 * float(np.sqrt(np.mean(r ** 2)))),
        "p95_abs_rel_%": g["rel"].apply(lambda r: 100 * float(np.percentile(np.abs(r), 95))),
        "mean_rel_%": g["rel"].mean() * 100,
        "p95_abs_um": g["diff_um"].apply(lambda r: float(np.percentile(np.abs(r), 95))),
    })


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--space-dir", default="results/simulated_space/scale_free")
    ap.add_argument("--per-cause", type=int, default=20)
    ap.add_argument("--seed", type=int, default=1000)
    ap.add_argument("--solvers", nargs="+", default=["refined", "quad9"])
    ap.add_argument("--calculix-per-cause", type=int, default=0,
                    help="also CalculiX on the first N draws of each cause (it refuses "
                         "pre-tension)")
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--cache", default="benchmarks/out/diagnose_confusion_fe")
    ap.add_argument("--out", default="benchmarks/out/discretisation_error.csv")
    args = ap.parse_args(argv)

    from skinsuction.space import read_ray_spaces

    space_dir = args.space_dir
    spaces = read_ray_spaces(space_dir)
    truths = ["none", *[n for n in spaces if n != "neo_hookean"]]
    jobs = []
    for k, truth in enumerate(truths):
        for i in range(args.per_cause):
            solvers = list(args.solvers)
            if i < args.calculix_per_cause and truth != "pre_tension":
                solvers.append("calculix")
            jobs.append((truth, args.seed + 100000 * k + i, space_dir, solvers, args.cache))
    print(f"{len(jobs)} draws, solvers {args.solvers}"
          f"{' + calculix on ' + str(args.calculix_per_cause) + ' a cause' if args.calculix_per_cause else ''}",
          flush=True)
    t0 = time.perf_counter()
    rows = []
    if args.workers > 1:
        from concurrent.futures import ProcessPoolExecutor

        with ProcessPoolExecutor(args.workers) as pool:
            for i, r in enumerate(pool.map(curves_of, jobs), 1):
                rows += r
                print(f"  {i}/{len(jobs)} ({time.perf_counter() - t0:.0f} s)", flush=True)
    else:
        for i, job in enumerate(jobs, 1):
            rows += curves_of(job)
            print(f"  {i}/{len(jobs)} ({time.perf_counter() - t0:.0f} s)", flush=True)
    df = pd.DataFrame(rows)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    df.to_csv(out, index=False)
    pd.set_option("display.width", 160)
    print("\nM_solver / M_space - 1 per solver, probe and load band (mbar/MPa):")
    print(table(df).to_string(float_format=lambda x: f"{x:.3g}"))
    cpu = df.groupby(["solver", "seed", "truth"])["cpu_seconds"].first().groupby("solver")
    print("\nCPU per draw (both probes), median:", cpu.median().round(1).to_dict())
    print(f"total {time.perf_counter() - t0:.0f} s; points written to {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
