"""Speed of `skinsuction study`: N measurements (both probes) identified with intervals, and diagnosed.

Builds a long CSV of N measurements from the shipped synthetic study (its 59
readable measurements, cycled, each copy with fresh noise of its own so that no
two curves are equal), then times `run_study` on the scale-free space:
identification with intervals of all N, then identification and diagnosis of
the first `--diagnose-n`.  Prints wall times, per-measurement CPU and the
projected time of N diagnoses.

    python benchmarks/study_speed.py [--n 1000] [--diagnose-n 100] [--workers 2]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np


def long_csv(n: int, out: Path, seed: int = 0) -> Path:
    from skinsuction.cohort import discover

    base = [e for e, _ in discover("data/synthetic_study") if e.data is not None]
    rng = np.random.default_rng(seed)
    lines = ["subject,visit,group,probe_mm,pressure_mbar,deflection_mm"]
    for k in range(n):
        e = base[k % len(base)]
        for c in e.data.curves:
            m = c.deflection_mm + rng.normal(0, 0.5e-3, c.deflection_mm.size) * (c.pressure_mbar > 0)
            lines += [f"B{k:05d},{e.ids['visit']},{e.ids['group']},{c.probe_mm:g},{p:g},{v:.5f}"
                      for p, v in zip(c.pressure_mbar, m)]
    out.write_text("\n".join(lines) + "\n")
    return out


def main(argv=None):
    from skinsuction.cohort import run_study

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1000)
    ap.add_argument("--diagnose-n", type=int, default=100)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--space", default="results/simulated_space/scale_free")
    args = ap.parse_args(argv)
    tmp = Path(tempfile.mkdtemp())
    path = long_csv(args.n, tmp / "study.csv")
    print(f"{args.n} measurements (6 and 2 mm, 51 pressures each), {args.workers} workers")
    runs = {"identify": (path, False)}
    if args.diagnose_n:
        runs["identify + diagnose"] = (long_csv(args.diagnose_n, tmp / "diag.csv"), True)
    for name, (p, diag) in runs.items():
        t0, c0 = time.perf_counter(), time.process_time()
        r = run_study(p, tmp / name.replace(" ", ""), space_dir=args.space, diagnose=diag,
                      workers=args.workers, progress=False, figures=False)
        wall = time.perf_counter() - t0
        import pandas as pd

        df = pd.read_parquet(tmp / name.replace(" ", "") / "curves.parquet")
        per = df["seconds"].astype(float)
        n = r["measurements"]
        print(f"{name}: {n} measurements in {wall:.1f} s wall ({wall / n * 1e3:.0f} ms each); "
              f"per measurement in its worker: median {per.median() * 1e3:.0f} ms, "
              f"p95 {per.quantile(0.95) * 1e3:.0f} ms; errors {r['errors']}")
        if diag:
            print(f"  projected for {args.n} diagnosed: {wall / n * args.n / 60:.1f} min")
    return 0


if __name__ == "__main__":
    main()
