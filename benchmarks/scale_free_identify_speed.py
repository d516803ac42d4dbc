"""Speed of one identification on the scale-free space (not a test).

Window focusing (N = 1000, Nb = 20, C = 1e-6) at the paper's test point
(X1d = 0.0055, X1h = 0.00041 MPa), its curves read from the space itself at
0, 2, ..., 100 mbar, for the four objectives, ``--repeats`` runs each (seeds
0, 1, ...). Prints the median wall time of a run, its CPU time, the iterations
and the time of tabulating the space at the protocol (once per protocol).

Usage::

    python benchmarks/scale_free_identify_speed.py [results/simulated_space/scale_free]
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np

from skinsuction.identify import (
    ratio_objective, single_objective, weighted_objective, window_focusing,
)
from skinsuction.space import NeoHookeanSlice, read_ray_spaces

TRUTH = (0.0055, 0.00041)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("space_dir", nargs="?", default="results/simulated_space/scale_free")
    parser.add_argument("--repeats", type=int, default=100)
    args = parser.parse_args(argv)

    base = read_ray_spaces(args.space_dir)["neo_hookean"]
    p = np.arange(0.0, 101.0, 2.0)
    slices = {q: NeoHookeanSlice(base, q) for q in (2.0, 6.0)}
    c0 = time.process_time()
    tables = {q: slices[q].interpolant_at(p) for q in slices}
    tab_ms = 1e3 * (time.process_time() - c0) / len(tables)
    theta = slices[6.0].from_moduli([TRUTH])
    c2, c6 = ((p, tables[q](theta)[0]) for q in (2.0, 6.0))
    objectives = {
        "single 6 mm": single_objective(slices[6.0], c6),
        "single 2 mm": single_objective(slices[2.0], c2),
        "weighted 0.5": weighted_objective(slices[2.0], c2, slices[6.0], c6, alpha=0.5),
        "ratio": ratio_objective(slices[2.0], c2, slices[6.0], c6),
    }
    print(f"space {args.space_dir}; python {platform.python_version()}, numpy {np.__version__}, "
          f"{platform.machine()}; tabulating at the protocol: {tab_ms:.0f} ms of CPU per probe")
    print(f"{'objective':14s} {'ms (wall)':>9s} {'ms (CPU)':>9s} {'iterations':>10s}")
    for name, objective in objectives.items():
        window_focusing(objective, seed=0)  # warm-up
        wall, its = [], []
        c0 = time.process_time()
        for seed in range(args.repeats):
            r = window_focusing(objective, seed=seed)
            wall.append(r.seconds)
            its.append(r.iterations)
        cpu = 1e3 * (time.process_time() - c0) / args.repeats
        print(f"{name:14s} {1e3 * np.median(wall):9.2f} {cpu:9.2f} {np.median(its):10.0f}")
    print("median wall time of one window focusing run; CPU: mean over the runs")


if __name__ == "__main__":
    main()
