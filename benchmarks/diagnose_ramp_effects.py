"""Single and paired effects in pressure ramps: named effect by effect? (prints figures;
asserts nothing).

The study of :func:`skinsuction.evaluation.ramp_effects_study` (its docstring gives
the classes, designs and the detectability); the workflow's rule
``ramp_effects_confusion`` runs the same with the configuration's settings.

    python benchmarks/diagnose_ramp_effects.py [--per-class 10] [--seed 0] [--workers 2]
    python benchmarks/diagnose_ramp_effects.py --summary benchmarks/out/diagnose_ramp_effects.csv
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import pandas as pd  # noqa: E402

from skinsuction.evaluation import (  # noqa: E402
    RAMP_CLASSES,
    RAMP_DESIGNS,
    ramp_effects_markdown,
    ramp_effects_study,
)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--per-class", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--designs", nargs="+", default=list(RAMP_DESIGNS))
    ap.add_argument("--classes", nargs="+", default=list(RAMP_CLASSES))
    ap.add_argument("--out", default="benchmarks/out/diagnose_ramp_effects.csv")
    ap.add_argument("--summary", metavar="CSV", help="print the summary of rows already run")
    args = ap.parse_args()
    if args.summary:
        print(ramp_effects_markdown(pd.read_csv(args.summary)))
        return
    start, done = time.perf_counter(), []

    def progress(row):
        done.append(row)
        print(f"  {len(done)}: {row['design']}: {row['truth']} -> {row.get('named')!r}"
              f"{' ERROR ' + row['error'] if row.get('error') else ''} "
              f"({time.perf_counter() - start:.0f} s)", flush=True)

    frame = ramp_effects_study(args.per_class, args.seed, args.designs, classes=args.classes,
                               processes=args.workers, progress=progress)
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    frame.to_csv(args.out, index=False)
    print(ramp_effects_markdown(frame))
    print(f"wall {time.perf_counter() - start:.0f} s on {args.workers} workers; rows in {args.out}")


if __name__ == "__main__":
    main()
