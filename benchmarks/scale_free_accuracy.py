"""Accuracy of the scale-free space against direct FE runs at random points.

    python benchmarks/scale_free_accuracy.py [--space-dir results/simulated_space/scale_free]
        [--points 120] [--seed 0] [--workers 2] [--out benchmarks/out/scale_free_accuracy.csv]
        [--models pre_tension ...] [--coordinate-range LO HI]
        [--x1d-range LO HI] [--protocol P_MAX STEP]

Draws random points across the whole domain of the space (every model, both
probes, X1h/X1d and the cause's value over their axes, X1d log-uniform in
0.005-0.15 MPa, protocols to 100, 300 or 500 mbar; see
skinsuction.evaluation), runs the FE model there on the rays' mesh with
their fallbacks, and compares it with the interpolated space at every pressure.
Prints the median, 95th percentile and maximum of the relative error, of the
absolute error and of the normalised error |dM| / max(0.2 % M, 0.3 µm) (the
target is met where it is <= 1), per model and overall, and where the maximum is.
Also per load band q = p / X1d (the even steps, and the tail beyond 20 000
mbar/MPa where the space has one), and side by side with the first load axis
(cubic Lagrange of M in q, benchmarks/_load_before.py) on the same FE runs. ``--x1d-range 0.007 0.03 --protocol 500 10``
measures the tail: 500 mbar on soft forearm skin. Asserts nothing.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd

_SPACES = None


def _init(space_dir):
    global _SPACES
    from skinsuction.space import read_ray_spaces

    _SPACES = read_ray_spaces(space_dir)


def _run(point):
    from skinsuction.evaluation import compare_point

    from _load_before import read_m_in_q

    rec = compare_point(_SPACES[point.model], point)
    rec["before_mm"] = read_m_in_q(_SPACES[point.model], point, rec["pressure_mbar"])
    return rec


def _stats(values):
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if not v.size:
        return "n/a"
    return (f"median {np.median(v):.3g}, 95th percentile {np.percentile(v, 95):.3g}, "
            f"max {v.max():.3g}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--space-dir", default="results/simulated_space/scale_free")
    ap.add_argument("--points", type=int, default=120)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default="benchmarks/out/scale_free_accuracy.csv")
    ap.add_argument("--models", nargs="+", default=None,
                    help="draw only these models (default: every model of the space)")
    ap.add_argument("--coordinate-range", nargs=2, type=float, default=None,
                    metavar=("LO", "HI"),
                    help="draw the cause's value in LO..HI (its own unit, e.g. lambda0 "
                         "1 1.1) instead of over its whole axis")
    ap.add_argument("--x1d-range", nargs=2, type=float, default=(0.005, 0.15),
                    metavar=("LO", "HI"), help="X1d drawn log-uniform in LO..HI (MPa)")
    ap.add_argument("--protocol", nargs=2, type=float, default=None,
                    metavar=("P_MAX", "STEP"),
                    help="every point's ramp: to P_MAX in STEP (mbar); default a mix of "
                         "100, 300 and 500 mbar")
    args = ap.parse_args(argv)

    from skinsuction.space import read_ray_spaces
    from skinsuction.evaluation import draw_points, normalised_error

    spaces = read_ray_spaces(args.space_dir)
    drawn = spaces if args.models is None else {m: spaces[m] for m in args.models}
    from skinsuction.evaluation import PROTOCOLS

    points = draw_points(drawn, args.points, seed=args.seed,
                         coordinate_range=args.coordinate_range,
                         x1d_range=tuple(args.x1d_range),
                         protocols=(tuple(args.protocol),) if args.protocol else PROTOCOLS)
    t0 = time.perf_counter()
    with ProcessPoolExecutor(args.workers, initializer=_init,
                             initargs=(args.space_dir,)) as pool:
        records = list(pool.map(_run, points))
    wall = time.perf_counter() - t0

    rows = []
    for r in records:
        for p, fe, sp, be in zip(r["pressure_mbar"], r["fe_mm"], r["space_mm"],
                                 r["before_mm"]):
            rows.append({k: r[k] for k in ("model", "probe_mm", "x1d", "ratio", "coordinate",
                                           "p_max")} | {"pressure_mbar": p, "fe_mm": fe,
                                                        "space_mm": sp, "before_mm": be})
    per_p = pd.DataFrame(rows)
    per_p["abs_error_um"] = 1e3 * (per_p["space_mm"] - per_p["fe_mm"]).abs()
    per_p["relative_error"] = per_p["abs_error_um"] / (1e3 * per_p["fe_mm"].abs())
    per_p["normalised_error"] = normalised_error(per_p["fe_mm"], per_p["space_mm"])
    per_p["before_relative_error"] = ((per_p["before_mm"] - per_p["fe_mm"]).abs()
                                      / per_p["fe_mm"].abs())
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    per_p.to_csv(out, index=False)
    pts = pd.DataFrame([{k: v for k, v in r.items() if not isinstance(v, list)}
                        for r in records])
    pts.to_csv(out.with_name(out.stem + "_points.csv"), index=False)

    print(f"{len(points)} random points ({args.seed=}), {len(per_p)} pressures compared; "
          f"FE runs {wall:.0f} s wall on {args.workers} workers")
    print(f"FE reached the last pressure at {int(pts['fe_converged'].sum())} points "
          f"({int((pts['fe_fallback'] > 0).sum())} on a fallback mesh)")
    print(f"pressures where the FE run has a value but the space has none (beyond its "
          f"coverage frontier): {int(pts['n_fe_only'].sum())} at "
          f"{int((pts['n_fe_only'] > 0).sum())} points; the reverse: "
          f"{int(pts['n_space_only'].sum())}")
    for label, g in [("all", per_p), *per_p.groupby("model")]:
        print(f"[{label}] {len(g)} pressures")
        print(f"  relative error: {_stats(g['relative_error'])}")
        both = g["before_relative_error"].notna()
        print(f"  side by side at the {int(both.sum())} pressures both load axes read: "
              f"log M in log q {_stats(g.loc[both, 'relative_error'])}; the first, M in q, "
              f"{_stats(g.loc[both, 'before_relative_error'])}")
        print(f"  absolute error (µm): {_stats(g['abs_error_um'])}")
        print(f"  normalised error |dM| / max(0.2 % M, 0.3 µm): "
              f"{_stats(g['normalised_error'])}; "
              f"within target at {100 * (g['normalised_error'] <= 1).mean():.1f} %")
    per_p["load"] = per_p["pressure_mbar"] / per_p["x1d"]
    bands = pd.cut(per_p["load"], [0, 5000, 10000, 20000, 40000, 71400 * 1.0001])
    print("per load band q = p/X1d (mbar/MPa): relative error")
    for band, g in per_p.groupby(bands, observed=True):
        print(f"  {band}: {len(g)} pressures, {_stats(g['relative_error'])}; within target "
              f"at {100 * (g['normalised_error'] <= 1).mean():.1f} %")
    worst = per_p.loc[per_p["normalised_error"].idxmax()]
    print("largest normalised error at: " + json.dumps(
        {k: (float(v) if isinstance(v, (float, np.floating)) else v)
         for k, v in worst.items()}))
    print(f"written: {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
