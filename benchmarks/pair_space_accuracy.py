"""Accuracy of the pair spaces: direct FE runs against the interpolated pair (prints
figures; asserts nothing).

Random points of each pair space of ``--space`` (default: the pairs that go with the
default space): a probe of the space, X1h/X1d log-uniform in 0.01-0.3 (the
physiological band of the confusion benchmarks; ``--ratio`` widens it), each cause's
axis coordinate uniform over the pair's nodes, X1d log-uniform in 0.03-0.15 MPa, a
ramp to 100, 300 or 500 mbar.  Each is solved by the FE model (the rays' mesh and
fallbacks) and compared with :class:`skinsuction.space.PairRayInterpolant` at every
pressure, as ``scale_free_accuracy.py`` does for the single causes.  Prints, per
pair and probe, the median and 95th percentile of the largest relative error over
each ramp and the share of points within 0.2 % of M (or 0.3 µm).

    OMP_NUM_THREADS=1 python benchmarks/pair_space_accuracy.py [--points 40] [--workers 2]
"""

from __future__ import annotations

import argparse
import math
import os
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")

from multiprocessing import get_context  # noqa: E402

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from skinsuction.evaluation._accuracy import PROTOCOLS, AccuracyPoint, compare_point  # noqa: E402
from skinsuction.space import pairs_for, read_ray_spaces, resolve_space  # noqa: E402

_PAIRS = {}


def _run(point):
    try:
        return compare_point(_PAIRS[point.model], point)
    except Exception as err:  # noqa: BLE001 - a failed point is counted, not dropped
        return {"model": point.model, "probe_mm": point.probe_mm, "error": str(err)[:200]}


def draw(pairs, n, seed, ratio):
    rng = np.random.default_rng(seed)
    out = []
    for name, space in pairs.items():
        a, b = space.pair.causes
        for _ in range(n):
            probe = float(rng.choice(space.probes_mm))
            p_max, step = PROTOCOLS[rng.integers(len(PROTOCOLS))]
            x1d = math.exp(rng.uniform(math.log(max(0.03, 1.2 * p_max / space.spec.load_max)),
                                       math.log(0.15)))
            out.append(AccuracyPoint(
                name, probe, x1d, 10 ** rng.uniform(*np.log10(ratio)),
                float(a.from_axis(rng.uniform(a.axis_nodes[0], a.axis_nodes[-1]))),
                p_max, step, coordinate2=float(b.from_axis(
                    rng.uniform(b.axis_nodes[0], b.axis_nodes[-1])))))
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--space", default=None)
    ap.add_argument("--points", type=int, default=40, help="points per pair")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--ratio", type=float, nargs=2, default=(0.01, 0.3))
    ap.add_argument("--out", default="benchmarks/out/pair_space_accuracy.csv")
    args = ap.parse_args()
    src = resolve_space(args.space)
    spec = read_ray_spaces(src.path)["neo_hookean"].spec
    _PAIRS.update(pairs_for(src.path, spec))
    if not _PAIRS:
        raise SystemExit(f"{src.path}: no pair spaces (build them: snakemake --cores 2 "
                         "scale_free_pairs)")
    points = draw(_PAIRS, args.points, args.seed, args.ratio)
    t0 = time.perf_counter()
    with get_context("fork").Pool(args.workers) as pool:
        rows = pool.map(_run, points)
    frame = pd.DataFrame(rows)
    os.makedirs(os.path.dirname(args.out), exist_ok=True)
    frame.drop(columns=[c for c in ("pressure_mbar", "fe_mm", "space_mm") if c in frame],
               errors="ignore").to_csv(args.out, index=False)
    print("| pair | probe | points | median max rel. error | 95th percentile | within "
          "target | FE failed |")
    print("|---|---|---|---|---|---|---|")
    for (name, probe), g in frame.groupby(["model", "probe_mm"]):
        ok = g[g.get("error").isna()] if "error" in g else g
        rel = 100 * ok["max_relative_error"].dropna()
        within = (ok["max_normalised_error"] <= 1).mean() if len(ok) else float("nan")
        print(f"| {name} | {probe:g} mm | {len(g)} | {rel.median():.2f} % | "
              f"{np.percentile(rel, 95) if len(rel) else float('nan'):.2f} % | "
              f"{100 * within:.0f} % | {len(g) - len(ok)} |")
    all_rel = 100 * frame["max_relative_error"].dropna()
    print(f"\nall: median {all_rel.median():.2f} %, 95th percentile "
          f"{np.percentile(all_rel, 95):.2f} %; wall {time.perf_counter() - t0:.0f} s on "
          f"{args.workers} workers")


if __name__ == "__main__":
    main()
