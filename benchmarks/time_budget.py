"""Time budget of a workflow run: jobs, CPU and wall seconds per rule, from its benchmark files.

Every costly rule has a `benchmark:` file (results/benchmarks/...tsv, Snakemake's
columns `s` and `cpu_time`).  This script maps each file to its rule through the
`benchmark:` patterns of workflow/rules/*.smk and prints a Markdown table: rule,
jobs, CPU-s, wall-s (summed over jobs), share of the CPU.

    python benchmarks/time_budget.py [RESULTS_DIR] [--workflow .]
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import pandas as pd


def benchmark_patterns(workflow_dir: Path) -> dict:
    """{rule: compiled regex of its benchmark path} from the rule files."""
    out = {}
    for smk in sorted((workflow_dir / "workflow" / "rules").glob("*.smk")):
        text = smk.read_text()
        for m in re.finditer(r"^\s*rule (\w+):(.*?)(?=^\s*rule \w+:|\Z)", text, re.S | re.M):
            name, body = m.group(1), m.group(2)
            b = re.search(r"benchmark:\s*\n\s*f?\"([^\"]+)\"", body)
            if not b:
                continue
            pattern = b.group(1).replace("{{", "{").replace("}}", "}")
            rx = re.escape(pattern)
            rx = re.sub(r"\\\{[^}]*\\\}", r"[^/]+", rx)
            rx = re.sub(r"\\\{SF_DIR\\\}", "results/simulated_space/scale_free", rx)
            out[name] = re.compile(rx + "$")
    return out


def time_budget(results_dir: Path, workflow_dir: Path) -> pd.DataFrame:
    patterns = benchmark_patterns(workflow_dir)
    rows = []
    for tsv in sorted((results_dir / "benchmarks").rglob("*.tsv")):
        rel = "results/" + tsv.relative_to(results_dir).as_posix()
        rule = next((r for r, rx in patterns.items() if rx.match(rel)), "(unmatched)")
        t = pd.read_csv(tsv, sep="\t")
        rows.append({"rule": rule, "wall_s": float(t["s"].iloc[-1]),
                     "cpu_s": float(t["cpu_time"].iloc[-1])})
    df = pd.DataFrame(rows)
    if df.empty:
        return df
    g = df.groupby("rule").agg(jobs=("wall_s", "size"), cpu_s=("cpu_s", "sum"),
                               wall_s=("wall_s", "sum"))
    g["share"] = g["cpu_s"] / g["cpu_s"].sum()
    return g.sort_values("cpu_s", ascending=False)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("results", nargs="?", default="results")
    ap.add_argument("--workflow", default=".")
    args = ap.parse_args(argv)
    g = time_budget(Path(args.results), Path(args.workflow))
    if g.empty:
        print("no benchmark files under", args.results)
        return 1
    print("| rule | jobs | CPU-s | wall-s (sum over jobs) | share of CPU |")
    print("|---|---|---|---|---|")
    for rule, r in g.iterrows():
        print(f"| {rule} | {int(r.jobs)} | {r.cpu_s:.0f} | {r.wall_s:.0f} | {100 * r.share:.1f} % |")
    print(f"| total | {int(g.jobs.sum())} | {g.cpu_s.sum():.0f} | {g.wall_s.sum():.0f} | 100 % |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
