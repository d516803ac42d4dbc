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
    from skinsuction.evaluation import UNDIAGNOSED, interval_coverage, wrong_untied

    df = pd.read_csv(path)
    ok = df[~df["named"].isin(UNDIAGNOSED)]
    coverage = interval_coverage(df).set_index("truth").to_dict("index")
    out = []
    for truth, g in ok.groupby("truth", sort=False):
        det = g if truth == "none" else g[g["detectable"].fillna(True).astype(bool)]
        row = {"run": path.stem, "truth": truth, "diagnosed": len(g),
               "named right (detectable)": _frac(int((det["named"] == truth).sum()), len(det)),
               "confident wrong cause": _frac(int(wrong_untied(g, truth).sum()), len(g))
               if truth != "none" else _frac(int((g["named"] != "none").sum()
                                                 - (g["verdict"] == "beyond_space").sum()),
                                             len(g))}
        cov = coverage.get(truth, {})
        for col in ("x1d", "x1h", "value"):
            n = cov.get(f"{col}_intervals")
            row[f"{col} covered"] = ("–" if n is None or n != n
                                     else _frac(round(cov[f"{col}_covered"] * n), int(n)))
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
