"""The error of the scale-free space against direct FE runs, per load q = p / X1d and probe.

Draws seeded virtual experiments across the physiological domain (as
``interval_coverage.py``: X1d log-uniform 0.005-0.15 MPa, X1h/X1d 0.003-0.1,
0-100 mbar), runs the FE model at each (both probes, the rays' mesh and
fallbacks; cached), and compares with the interpolated space at the truth.
Prints, per probe and load bin, the rms and 95th percentile of the relative
error and the 95th percentile in µm, and the rms profile in the form of
``skinsuction.identify.measured_fit.SPACE_ERROR_RMS`` (the bins' rms at their
centres, the end values repeated at q = 0 and 20 000).  The default seeds
(7000-7119) are not those of the coverage benchmark (5000-5199), so the
profile the intervals use is not fitted to the draws that measure their
coverage.

    python benchmarks/space_error_profile.py [--space DIR] [--first-seed 7000] [--draws 120]
        [--probes 2 4 6 8]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent))
import interval_coverage as ic  # noqa: E402  (the draws and the FE cache)

EDGES = [0, 1000, 2000, 4000, 7000, 10000, 14000, 20000]


def errors(space, cache: Path, seeds, probes=(2.0, 6.0)) -> pd.DataFrame:
    spec = space.probe(6.0).space.spec
    clean = ic.clean_curves(seeds, cache, dict(spec.mesh or {}), spec.fallback, probes)
    rows = []
    for s in seeds:
        x1d, x1h, _ = ic.draw(s)
        for probe in probes:
            fe = clean[s][probe]
            sl = space.probe(probe)
            sp = sl.interpolant_at(ic.PRESSURES)(sl.from_moduli([[x1d, x1h]]))[0]
            for p, a, b in zip(ic.PRESSURES[1:], fe[1:], sp[1:]):
                if np.isfinite(a) and np.isfinite(b) and a > 0:
                    rows.append((s, probe, p / x1d, (b - a) / a, 1e3 * (b - a)))
    return pd.DataFrame(rows, columns=["seed", "probe", "q", "rel", "err_um"])


def main(argv=None):
    from skinsuction.space import load_space

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--space", default="results/simulated_space/scale_free")
    ap.add_argument("--cache", default="results/benchmarks/space_error_profile_fe.json")
    ap.add_argument("--first-seed", type=int, default=7000)
    ap.add_argument("--draws", type=int, default=120)
    ap.add_argument("--probes", type=float, nargs="+", default=[2.0, 4.0, 6.0, 8.0])
    args = ap.parse_args(argv)
    df = errors(load_space(args.space), Path(args.cache),
                list(range(args.first_seed, args.first_seed + args.draws)), args.probes)
    df["bin"] = pd.cut(df["q"], EDGES)
    g = df.groupby(["probe", "bin"], observed=False)
    table = pd.DataFrame({
        "points": g.size(),
        "rms_rel_pct": 100 * g["rel"].agg(lambda x: float(np.sqrt(np.mean(x ** 2)))),
        "p95_rel_pct": 100 * g["rel"].agg(lambda x: float(np.quantile(np.abs(x), 0.95))),
        "p95_um": g["err_um"].agg(lambda x: float(np.quantile(np.abs(x), 0.95))),
    })
    print(table.round(4).to_string())
    centres = [0.5 * (a + b) for a, b in zip(EDGES[:-1], EDGES[1:])]
    print("\nSPACE_ERROR_LOADS =", tuple([0.0, *centres, float(EDGES[-1])]))
    for probe in sorted(args.probes, reverse=True):
        rms = [float(table.loc[(probe, b), "rms_rel_pct"]) / 100 for b in table.loc[probe].index]
        print(f"    {probe}: {tuple(float(f'{r:.2g}') for r in [rms[0], *rms, rms[-1]])},")
    return table


if __name__ == "__main__":
    main()
