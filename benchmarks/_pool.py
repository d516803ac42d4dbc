"""What the benchmarks share: their jobs run in processes, every row written to a CSV."""

from __future__ import annotations

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
