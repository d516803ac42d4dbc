"""Single and paired effects, named effect by effect? In Cutometer time curves, or with
``--ramps`` in pressure ramps (prints figures; asserts nothing).

The studies of :func:`skinsuction.evaluation.effects_confusion_study` and
:func:`skinsuction.evaluation.ramp_effects_study` (their docstrings give the classes,
designs and the detectability); the workflow's rules ``time_effects_confusion`` and
``ramp_effects_confusion`` run the same with the configuration's settings.

    python benchmarks/diagnose_effects_confusion.py [--ramps] [--per-class 10] [--seed 0] [--workers 2]
    python benchmarks/diagnose_effects_confusion.py [--ramps] --summary benchmarks/out/diagnose_effects_confusion.csv
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import pandas as pd  # noqa: E402

from skinsuction.evaluation import (  # noqa: E402
    EFFECT_DESIGNS,
    RAMP_DESIGNS,
    effects_confusion_markdown,
    effects_confusion_study,
    ramp_effects_markdown,
    ramp_effects_study,
)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--ramps", action="store_true", help="pressure ramps, not mode 1")
    ap.add_argument("--per-class", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--designs", nargs="+", default=None)
    ap.add_argument("--out", default=None)
    ap.add_argument("--summary", metavar="CSV", help="print the summary of rows already run")
    args = ap.parse_args()
    study, markdown, designs, name = (
        (ramp_effects_study, ramp_effects_markdown, RAMP_DESIGNS, "diagnose_ramp_effects")
        if args.ramps else
        (effects_confusion_study, effects_confusion_markdown, EFFECT_DESIGNS,
         "diagnose_effects_confusion"))
    out = args.out or f"benchmarks/out/{name}.csv"
    if args.summary:
        print(markdown(pd.read_csv(args.summary)))
        return
    start, done = time.perf_counter(), []

    def progress(row):
        done.append(row)
        print(f"  {len(done)}: {row['design']}: {row['truth']} -> {row.get('named')!r}"
              f"{' ERROR ' + row['error'] if row.get('error') else ''} "
              f"({time.perf_counter() - start:.0f} s)", flush=True)

    frame = study(args.per_class, args.seed, args.designs or list(designs),
                  processes=args.workers, progress=progress)
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    frame.to_csv(out, index=False)
    print(markdown(frame))
    print(f"wall {time.perf_counter() - start:.0f} s on {args.workers} workers; rows in {out}")


if __name__ == "__main__":
    main()
