"""What the benchmarks share: their jobs run in processes, every row written to a CSV."""

from __future__ import annotations

import argparse
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import pandas as pd


def run_rows(func, jobs, workers: int, out) -> tuple:
    """``(rows, seconds)``: ``func`` on every job in ``workers`` processes, the rows (one
    dict per job) written to ``out`` (CSV, its folder created) and returned as a frame."""
    t0 = time.perf_counter()
    with ProcessPoolExecutor(workers) as pool:
        rows = pd.DataFrame(list(pool.map(func, jobs)))
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    rows.to_csv(out, index=False)
    return rows, time.perf_counter() - t0


def mm_range(text) -> tuple:
    """``LO,HI`` (mm) of a command-line option: the range a benchmark draws a length from."""
    lo, hi = (float(v) for v in text.split(","))
    if not 0 < lo <= hi:
        raise argparse.ArgumentTypeError(f"{text!r}: want LO,HI with 0 < LO <= HI (mm)")
    return lo, hi
