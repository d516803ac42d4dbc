"""One table from several runs of ``benchmarks/diagnose_confusion.py --solver ...``.

For each run (a CSV of its rows): per true cause the draws diagnosed, the rate named
right over the detectable draws, the confident wrong causes (named another cause, not
tied, not at the space's edge: ``skinsuction.evaluation.wrong_untied``) over the
diagnosed draws, and the coverage of the 95 % intervals of X1d, X1h and the cause's
parameter over the draws named right.  Prints Markdown; asserts nothing.

    python benchmarks/other_solver_table.py benchmarks/out/other_solver/*.csv
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import pandas as pd


def _frac(k: int, n: int) -> str:
    return f"{k}/{n}" if n else "–"


def run_rows(path: Path) -> list:
    from skinsuction.evaluation import UNDIAGNOSED, wrong_untied

    df = pd.read_csv(path)
    ok = df[~df["named"].isin(UNDIAGNOSED)]
    out = []
    for truth, g in ok.groupby("truth", sort=False):
        det = g if truth == "none" else g[g["detectable"].fillna(True).astype(bool)]
        right = g[g["named"] == truth]
        row = {"run": path.stem, "truth": truth, "diagnosed": len(g),
               "named right (detectable)": _frac(int((det["named"] == truth).sum()), len(det)),
               "confident wrong cause": _frac(int(wrong_untied(g, truth).sum()), len(g))
               if truth != "none" else _frac(int((g["named"] != "none").sum()
                                                 - (g["verdict"] == "beyond_space").sum()),
                                             len(g))}
        for col, true in (("x1d", "x1d"), ("x1h", "x1h"), ("value", "value")):
            lo, hi = f"ci_{col}_lo", f"ci_{col}_hi"
            if lo not in right or (truth == "none" and col == "value"):
                row[f"{col} covered"] = "–"
                continue
            r = right[right[lo].notna()]
            cover = ((r[lo] <= r[true] * (1 + 1e-9)) & (r[true] <= r[hi] * (1 + 1e-9))).sum()
            row[f"{col} covered"] = _frac(int(cover), len(r))
        out.append(row)
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("csv", nargs="+", type=Path)
    args = ap.parse_args(argv)
    rows = [r for p in args.csv for r in run_rows(p)]
    cols = list(rows[0]) if rows else []
    print("| " + " | ".join(cols) + " |")
    print("|" + "---|" * len(cols))
    for r in rows:
        print("| " + " | ".join(str(r[c]) for c in cols) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
