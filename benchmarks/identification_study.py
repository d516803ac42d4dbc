"""The identification study in one go, without the workflow (not a test).

Prints, for a simulated space and the paper's test point X1d = 0.0055 MPa,
X1h = 0.00041 MPa, the Figure 4 numbers (errors of 100 single-probe
identifications), the weighted objective against alpha (Figure 7), the ratio
identification (Figure 8), the timing table and the optimiser comparison --
the same package functions as the workflow rules, with the test curve taken
from the interpolated space (the paper's variant) and, with ``--fe``, from
direct FE runs at the test point (the honest variant; two FE solves).

Usage::

    python benchmarks/identification_study.py                       # surrogate space
    python benchmarks/identification_study.py results/simulated_space/paper.parquet --fe
    python benchmarks/identification_study.py SPACE --repeats 20 --refinement 0.5 --fe
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import pandas as pd

from skinsuction.identify import analytic_surrogate_space
from skinsuction.space import evaluate
from skinsuction.paper import (
    StudySetup,
    alpha_sweep,
    alpha_threshold,
    load_spaces,
    optimiser_comparison,
    ratio_study,
    single_probe_study,
    summarise_runs,
    target_of,
    timing_study,
)

pd.set_option("display.width", 200)
pd.set_option("display.max_columns", 20)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("space", nargs="?", help="simulated-space Parquet (default: surrogate)")
    parser.add_argument("--fe", action="store_true",
                        help="also identify direct FE curves at the test point")
    parser.add_argument("--refinement", type=float, default=None,
                        help="mesh refinement of the FE test curves (default: the space's)")
    parser.add_argument("--repeats", type=int, default=100)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--config", default="config/config.yaml",
                        help="the test point is identification.target of this config")
    args = parser.parse_args(argv)
    import yaml

    with open(args.config, encoding="utf-8") as f:
        TARGET = target_of(yaml.safe_load(f)["identification"])  # noqa: N806

    if args.space:
        spaces = load_spaces(args.space)
        from skinsuction.space import read_space

        meta = read_space(args.space).metadata
        mesh = dict(meta.get("mesh") or {})
    else:
        spaces = {p: analytic_surrogate_space(p) for p in (2.0, 6.0)}
        mesh = {}
    curves = {"space": {p: (s.pressure_mbar, evaluate(s, [TARGET])[0]) for p, s in spaces.items()}}
    if args.fe:
        from skinsuction.model import Skin, simulate

        if args.refinement is not None:
            mesh["refinement"] = args.refinement
        curves["fe"] = {}
        for p, s in spaces.items():
            t0 = time.perf_counter()
            c = simulate(Skin.two_layer(*TARGET), p, pressures_mbar=s.pressure_mbar, mesh=mesh)
            ok = np.isfinite(c.deflection_mm)
            curves["fe"][p] = (s.pressure_mbar[ok], np.asarray(c.deflection_mm)[ok])
            print(f"FE test curve {p:g} mm: {time.perf_counter() - t0:.1f} s, mesh {mesh}, "
                  f"converged={c.converged}")
    setup = StudySetup(spaces, curves, TARGET)
    cols = ["source", "objective", "x1d_error_mean_pct", "x1h_error_mean_pct",
            "x1d_error_max_pct", "x1h_error_max_pct", "success_fraction", "iterations_median"]

    print("\nFigure 4: single-probe identifications")
    runs = single_probe_study(setup, repeats=args.repeats, seed=args.seed)
    print(summarise_runs(runs, TARGET)[cols].round(3).to_string(index=False))

    print("\nFigure 7: weighted objective against alpha")
    runs = alpha_sweep(setup, np.linspace(0, 1, 11), repeats=args.repeats, seed=args.seed)
    table = summarise_runs(runs, TARGET, ("source", "alpha"))
    print(table[["source", "alpha", *cols[2:]]].round(3).to_string(index=False))
    print(alpha_threshold(table).to_string(index=False))

    print("\nFigure 8: ratio objective")
    runs = ratio_study(setup, repeats=args.repeats, seed=args.seed)
    print(summarise_runs(runs, TARGET)[cols].round(3).to_string(index=False))

    print("\nTiming (median per identification)")
    _, table = timing_study(setup, repeats=args.repeats, seed=args.seed)
    print(table[["source", "objective", "iterations_median", "ms_median", "cpu_ms_median",
                 "paper_iterations", "paper_seconds"]].round(3).to_string(index=False))

    print("\nOptimisers on the space (6 mm probe alone)")
    _, table = optimiser_comparison(setup, runs=min(args.repeats, 100), seed=args.seed)
    print(table[["source", "method", "runs", "success_truth", "success_minimum",
                 "evaluations_median", "ms_median", "x1d_median", "x1h_median"]]
          .to_string(index=False))


if __name__ == "__main__":
    main()
