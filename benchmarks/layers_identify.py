"""`identify` alone on the ramps of the layers study: CPU per subject, and the truth.

    python benchmarks/layers_identify.py [--folder results/studies_input/layers]
        [--truth results/studies_input/layers_truth.csv] [--subjects N] [--space DIR]
        [--cache DIR] [--out benchmarks/out/layers_identify.csv]

Each ramp of the study (two probes, both layers given with an sd of 0.1 mm; made by
`snakemake --cores 2 layers_study`) is identified as the study does it (weighted
objective, 2 runs polished, 95 % intervals with the thicknesses' sd), the i-th with
seed i, one after the other in this process, from an empty ray cache (a fresh
temporary folder unless --cache). Prints the CPU of each identification (median,
95th percentile, max, all), how often the 95 % intervals of X1d and X1h hold the
truth, and the X1d error. Asserts nothing.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--folder", default="results/studies_input/layers")
    ap.add_argument("--truth", default="results/studies_input/layers_truth.csv")
    ap.add_argument("--subjects", type=int, default=None, help="the first N ramps")
    ap.add_argument("--space", default=None, help="scale-free space (default: the shipped)")
    ap.add_argument("--cache", default=None, help="ray cache (default: a fresh one)")
    ap.add_argument("--out", default="benchmarks/out/layers_identify.csv")
    a = ap.parse_args(argv)
    files = sorted(Path(a.folder).glob("*_ramp.csv"))[:a.subjects]
    if not files:
        raise SystemExit(f"{a.folder}: no *_ramp.csv (make them: snakemake --cores 2 "
                         "layers_study)")
    truth = pd.read_csv(a.truth)
    truth = truth[truth["measurement"] == "ramp"].set_index("subject")
    os.environ["SKINSUCTION_CACHE"] = a.cache or tempfile.mkdtemp(prefix="rays_")
    from skinsuction.identify.measured_fit import identify_measured

    rows, out = [], Path(a.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    for i, path in enumerate(files):
        subject = path.name.split("_")[0]
        t = truth.loc[subject]
        c0 = time.process_time()
        r = identify_measured(path, a.space, objective="weighted", repeats=2, seed=i)
        cpu = time.process_time() - c0
        iv, ih = r.intervals["X1d"], r.intervals["X1h"]
        rows.append({"subject": subject, "cpu_s": cpu, "x1d_mpa": r.x1d_mpa,
                     "x1d_lower": iv["lower"], "x1d_upper": iv["upper"],
                     "x1d_truth": t["x1d_mpa"], "x1d_error": r.x1d_mpa / t["x1d_mpa"] - 1,
                     "x1d_holds": bool(iv["lower"] <= t["x1d_mpa"] <= iv["upper"]),
                     "x1h_holds": bool(ih["lower"] <= t["x1h_mpa"] <= ih["upper"])})
        pd.DataFrame(rows).to_csv(out, index=False)
    d = pd.DataFrame(rows)
    cpu, err = d["cpu_s"], d["x1d_error"].abs()
    print(f"{len(d)} ramps of {a.folder}, space {a.space or 'shipped'}")
    print(f"CPU per identify: median {cpu.median():.2f} s, 95th pct "
          f"{np.percentile(cpu, 95):.2f} s, max {cpu.max():.1f} s, all {cpu.sum():.0f} s")
    print(f"95 % intervals hold the truth: X1d {100 * d['x1d_holds'].mean():.1f} %, "
          f"X1h {100 * d['x1h_holds'].mean():.1f} %")
    print(f"X1d error: median {100 * err.median():.2f} %, 95th pct "
          f"{100 * np.percentile(err, 95):.1f} %")


if __name__ == "__main__":
    main()
