"""Speed of the window focusing identification: vectorised vs naive (not a test).

Prints the time of one identification (paper settings N = 1000, Nb = 20,
C = 1e-6 µm) and of 100 repeated identifications (paper section 3.2) with

* fast:  ``skinsuction.identify`` (all N candidates of an iteration in one call);
* naive: the same algorithm, but every candidate is interpolated on its own in a
  Python loop by ``scipy.interpolate.RegularGridInterpolator(method="cubic")``
  (the space is interpolated to the measured pressures once, as in the fast
  path, so the comparison isolates the per-candidate evaluation).

Both are measured in the same run; the naive time of 100 repeats is
extrapolated from ``--naive-runs`` identifications.  The curve to identify is
the surrogate (or real) 6 mm space interpolated at X1d = 0.0055 MPa,
X1h = 0.00041 MPa (the paper's test case).

Usage::

    python benchmarks/identify_speed.py                      # surrogate 11 x 11 x 51 space
    python benchmarks/identify_speed.py results/simulated_space/paper.parquet --probe 6
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np
from scipy.interpolate import RegularGridInterpolator

from skinsuction.evaluation import differential_evolution_fit, least_squares_from_random_starts
from skinsuction.identify import analytic_surrogate_space, identify_repeated, single_objective, window_focusing
from skinsuction.space import GriddedSpace, evaluate, interpolate_pressure

TRUTH = (0.0055, 0.00041)


class NaiveObjective:
    """Eq. 4 with one scipy interpolator call per candidate, in a Python loop."""

    error_unit = "µm"

    def __init__(self, space: GriddedSpace, pressure_mbar, deflection_mm):
        at_p = interpolate_pressure(space, pressure_mbar)
        self.interp = RegularGridInterpolator(
            (at_p.x1d, at_p.x1h), at_p.deflection_mm, method="cubic"
        )
        self.measured = np.asarray(deflection_mm, dtype=float)
        self.lower, self.upper = space.lower, space.upper
        self.n_points = self.measured.size

    def __call__(self, candidates):
        out = np.empty(len(candidates))
        for k, x in enumerate(candidates):
            d = self.measured - self.interp(x)[0]
            out[k] = 0.5 * d @ d
        out[np.isnan(out)] = np.inf
        return out

    def error(self, j):
        return 1000.0 * np.sqrt(2.0 * j) / self.n_points


def load_space(path, probe_mm):
    if path is None:
        return analytic_surrogate_space(probe_mm), "analytic surrogate"
    from skinsuction.space import read_space

    return GriddedSpace.from_space(read_space(path), probe_mm), str(path)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("space", nargs="?", help="simulated-space Parquet file (default: surrogate)")
    parser.add_argument("--probe", type=float, default=6.0, help="probe diameter, mm (default 6)")
    parser.add_argument("--repeats", type=int, default=100)
    parser.add_argument("--naive-runs", type=int, default=2,
                        help="naive identifications actually run (default 2)")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)

    space, label = load_space(args.space, args.probe)
    p = space.pressure_mbar
    m = evaluate(space, [TRUTH], p)[0]
    print(f"space: {label}, probe {space.probe_mm:g} mm, grid {space.shape}, "
          f"curve of {p.size} points at X1d={TRUTH[0]}, X1h={TRUTH[1]}")
    print(f"python {platform.python_version()}, numpy {np.__version__}, {platform.machine()}")

    fast = single_objective(space, (p, m))
    window_focusing(fast, seed=args.seed)  # warm-up
    t0, c0 = time.perf_counter(), time.process_time()
    rep = identify_repeated(fast, repeats=args.repeats, seed=args.seed)
    fast_total, fast_cpu = time.perf_counter() - t0, time.process_time() - c0
    per_id = np.array([r.seconds for r in rep.results])
    fast_ms = 1e3 * fast_total / args.repeats
    print(f"\nfast : {fast_ms:8.2f} ms per identification (wall, mean; median "
          f"{1e3 * np.median(per_id):.2f}, min {1e3 * per_id.min():.2f}; CPU "
          f"{1e3 * fast_cpu / args.repeats:.2f}), {rep.iterations.mean():.1f} iterations, "
          f"{args.repeats} repeats in {fast_total:.3f} s")
    print(f"       estimate mean {rep.mean.tolist()}, relative std {rep.relative_spread.tolist()}")

    naive = NaiveObjective(space, p, m)
    naive_s, evaluations = [], 0
    c0 = time.process_time()
    for k in range(args.naive_runs):
        r = window_focusing(naive, seed=args.seed + k)
        naive_s.append(r.seconds)
        evaluations += r.n_evaluations
    naive_cpu = (time.process_time() - c0) / args.naive_runs
    naive_mean = float(np.mean(naive_s))
    print(f"naive: {1e3 * naive_mean:8.1f} ms per identification (wall, mean of {args.naive_runs}; "
          f"CPU {1e3 * naive_cpu:.1f}; {1e6 * sum(naive_s) / evaluations:.1f} µs per candidate), "
          f"{args.repeats} repeats ≈ {naive_mean * args.repeats:.1f} s (extrapolated)")
    print(f"       last naive estimate {r.estimate.tolist()} (cubic spline, not Lagrange)")
    print(f"ratio naive / fast: {1e3 * naive_mean / fast_ms:.0f}x (wall), "
          f"{naive_cpu / (fast_cpu / args.repeats):.0f}x (CPU)")

    print("\nbaselines on the same objective (one run each):")
    for name, fit in (("least_squares x10 starts", least_squares_from_random_starts),
                      ("differential_evolution", differential_evolution_fit)):
        b = fit(fast, seed=args.seed)
        print(f"  {name:26s} {1e3 * b.seconds:8.1f} ms, {b.n_evaluations:6d} candidates, "
              f"success={b.success}, estimate {b.estimate.tolist()}")


if __name__ == "__main__":
    main()
