"""Why the soft corner of the paper grid stops before 100 mbar (prints evidence;
asserts nothing).

For grid points that stop on the default model, the pressure where each model
variant stops, the largest principal stretch there (and where), and dM/dp at the
last equilibrium against the initial slope. A physical limit point would stop
every variant at the same pressure with dM/dp growing without bound; a stop that
moves with the element size or type at a finite slope is numerical.

    OMP_NUM_THREADS=1 python benchmarks/soft_corner.py [--processes 2]
"""

import argparse
import os
from multiprocessing import Pool

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from skinsuction.model import Skin, SuctionTest  # noqa: E402

POINTS = [  # (probe_mm, X1d, X1h) in MPa
    (2, 0.001, 1.01e-3),
    (6, 0.001, 1.01e-3),
    (6, 0.010, 1e-5),
]
GRID = {"corner": "grid", "edge_size": 0.006}  # the tensor grid up to the edge
VARIANTS = {
    "default (fan, quad8)": {},
    "fan, quad9, full": {"element": "quad9", "quadrature": "full"},
    "grid (quad8, reduced)": GRID,
    "grid, corner x2": {**GRID, "edge_size": 0.012},
    "grid, corner x3.3": {**GRID, "edge_size": 0.02},
    "grid, quad9, full": {**GRID, "element": "quad9", "quadrature": "full"},
    "grid, rounded R = 0.05 a": {**GRID, "edge_radius": 0.05},
    "grid, rounded R = 0.1 a": {**GRID, "edge_radius": 0.1},
}


def run(job):
    (probe, x1d, x1h), name = job
    model = SuctionTest(Skin.two_layer(x1d, x1h), probe=probe, mesh=VARIANTS[name])
    curve = model.run()
    M = curve.deflection_mm
    ok = np.flatnonzero(np.isfinite(M))
    slope = np.diff(M[ok]) / np.diff(curve.pressure_mbar[ok])
    stretch, (z, r) = model.largest_stretch()
    return (probe, x1d, x1h, name, curve.last_converged_mbar, stretch, z, r,
            slope[-1] / slope[0], curve.seconds)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--processes", type=int, default=2)
    args = parser.parse_args()
    jobs = [(point, name) for point in POINTS for name in VARIANTS]
    print(f"{'probe':>5} {'X1d':>6} {'X1h':>8}  {'variant':<26} {'stops at':>8} "
          f"{'stretch':>7} {'at z, r (mm)':>15} {'slope':>6} {'s':>5}")
    with np.errstate(all="ignore"), Pool(args.processes) as pool:
        for probe, x1d, x1h, name, last, stretch, z, r, slope, seconds in pool.imap(run, jobs):
            stop = "100 (all)" if last >= 100 else f"{last:g}"
            print(f"{probe:>5} {x1d:>6g} {x1h:>8.3g}  {name:<26} {stop:>8} {stretch:>7.2f} "
                  f"{z:>7.3f},{r:>7.3f} {slope:>6.2f} {seconds:>5.1f}")


if __name__ == "__main__":
    main()
