"""Diagnoses with the causes' rays read first against every ray over the tolerance solved.

    python benchmarks/cause_rays_read_first.py [--folder results/studies_input/layers]
        [--curves results/studies/layers/curves.parquet] [--min-seconds 5]
        [--margin 2] [--workers 2] [--out benchmarks/out/cause_rays_read_first.csv]

Each ramp of the layers study (made by `snakemake --cores 2 layers_study`) is
diagnosed as the study does it (one run per fit, no holdout, the seed the study
gives it: 2 k - 1 for subject k), twice: with the causes' rays read off their
geometry spaces first and solved only where a cause's fit lies under --margin in
delta BIC (the default), and with every ray over the error estimate's tolerance
solved at once (`cause_rays_margin_bic=None`, as before). Each way has a ray cache
of its own, fresh. --min-seconds keeps the ramps whose row in --curves took longer
(the ones that solve rays). Prints, per cause whose rays were read over the
tolerance, the ray count, the largest error estimate, its delta BIC read and
solved; then whether any verdict or estimate differs, and the CPU of both ways.
Asserts nothing.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import pandas as pd
from _pool import run_rows


def _one(job):
    path, seed, margin, cache = job
    os.environ["SKINSUCTION_CACHE"] = cache
    from skinsuction.diagnose import Settings, diagnose_file
    from skinsuction.space import BASELINE, OnDemandRays, geometry_file_for, read_ray_spaces
    from skinsuction.space import resolve_space

    src = resolve_space(None).path
    spaces = read_ray_spaces(src)
    solver = OnDemandRays(spaces[BASELINE].spec, cache_dir=cache, progress=None,
                          geometry=geometry_file_for(src))
    settings = Settings.from_config(None, {"holdout": False, "repeats": 1,
                                           "intervals": "cause"},
                                    seed=seed, cause_rays_margin_bic=margin)
    t0 = time.process_time()
    r = diagnose_file(path, spaces=spaces, settings=settings, on_demand=solver)
    row = {"file": Path(path).name, "margin": margin, "cpu_s": time.process_time() - t0,
           "verdict": r["verdict"], "cause_named": r["cause"],
           **{k: v for k, v in r["baseline"]["parameters"].items()}}
    for c in r["candidates"]:
        d = c.get("rays_deferred") or {}
        row.update({f"{c['cause']}.delta_bic": c["delta_bic"],
                    f"{c['cause']}.extra": c["extra_parameter"]["value"],
                    f"{c['cause']}.rays_read_over": d.get("rays", 0),
                    f"{c['cause']}.estimate": d.get("largest_error_estimate"),
                    f"{c['cause']}.delta_bic_read": d.get("delta_bic_read"),
                    f"{c['cause']}.solved": d.get("solved")})
    if r.get("extended"):
        row.update({f"chosen.{k}": v for k, v in r["extended"]["parameters"].items()})
    return row


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--folder", default="results/studies_input/layers")
    ap.add_argument("--curves", default="results/studies/layers/curves.parquet")
    ap.add_argument("--min-seconds", type=float, default=0.0)
    ap.add_argument("--margin", type=float, default=2.0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default="benchmarks/out/cause_rays_read_first.csv")
    a = ap.parse_args(argv)
    files = sorted(Path(a.folder).glob("*_ramp.csv"))
    if not files:
        raise SystemExit(f"{a.folder}: no *_ramp.csv (make them: snakemake --cores 2 "
                         "layers_study)")
    if a.min_seconds > 0:
        rows = pd.read_parquet(a.curves)
        slow = set(rows[(rows.measurement == "ramp") & (rows.seconds > a.min_seconds)].file)
        files = [f for f in files if f.name in slow or str(f) in slow]
    caches = [tempfile.mkdtemp(prefix="read_first_"), tempfile.mkdtemp(prefix="solved_")]
    jobs = [(str(f), 2 * int(f.name[1:4]) - 1, m, cache) for m, cache in
            zip((a.margin, None), caches) for f in files]
    print(f"{len(files)} ramps, each diagnosed twice", flush=True)
    df, seconds = run_rows(_one, jobs, a.workers, a.out)
    first = df[df.margin.notna()].set_index("file")
    solved = df[df.margin.isna()].set_index("file")
    causes = sorted({c.split(".")[0] for c in df.columns if c.endswith(".delta_bic")})
    table = []
    for cause in causes:
        over = first[first[f"{cause}.rays_read_over"] > 0]
        for f, r in over.iterrows():
            table.append({"ramp": f, "cause": cause, "rays": int(r[f"{cause}.rays_read_over"]),
                          "largest estimate %": 100 * r[f"{cause}.estimate"],
                          "dBIC read": r[f"{cause}.delta_bic_read"],
                          "solved again": bool(r[f"{cause}.solved"]),
                          "dBIC all solved": solved.loc[f, f"{cause}.delta_bic"]})
    t = pd.DataFrame(table)
    if len(t):
        t["moved"] = t["dBIC read"] - t["dBIC all solved"]
        print(t.round(4).to_string(index=False))
        kept = t[~t["solved again"]]
        print(f"\ncauses read over the tolerance: {len(t)}; solved again: "
              f"{int(t['solved again'].sum())}; delta BIC moved by the read rays: max "
              f"{t['moved'].abs().max():.4f}; of those left as read, the lowest delta BIC "
              f"read {kept['dBIC read'].min() if len(kept) else float('nan'):.3f}")
    same = (first.verdict == solved.loc[first.index].verdict)
    print(f"verdicts the same: {int(same.sum())} of {len(first)}")
    for k in ("X1d", "X1h"):
        rel = (first[k] / solved.loc[first.index, k] - 1).abs()
        print(f"{k} of the neo-Hookean fit, largest relative difference: {rel.max():.2e}")
    chosen = [c for c in df.columns if c.startswith("chosen.")]
    if chosen:
        rel = (first[chosen] / solved.loc[first.index, chosen] - 1).abs().max().max()
        print(f"the named cause's parameters, largest relative difference: {rel:.2e}")
    print(f"CPU: read first {first.cpu_s.sum():.0f} s, every ray solved {solved.cpu_s.sum():.0f} s"
          f" (median {first.cpu_s.median():.2f} / {solved.cpu_s.median():.2f} s); "
          f"{seconds:.0f} s wall")


if __name__ == "__main__":
    main()
