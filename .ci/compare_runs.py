#!/usr/bin/env python
"""Compare the simulated-space databases of two runs of the workflow.

    python .ci/compare_runs.py RUN_A RUN_B [DATABASE ...] [--rtol 1e-9]

RUN_A and RUN_B are working copies in which the workflow ran; each DATABASE is a
path relative to both (default: every results/simulated_space/*.parquet and
results/simulated_space/scale_free/*.parquet found in either).  Two kinds are
understood, told apart by their columns:

* a grid space (skinsuction.space.assemble_space): one curve per point_id;
  the points, their `converged` flags and `last_converged_mbar` must be equal;
* a scale-free space (skinsuction.space.assemble_ray_space): one ray
  per (probe_mm, ratio, coordinate); the rays and their `converged` flags (the
  per-ray solver record in the file's metadata) must be equal;
* a geometry space (skinsuction.space.assemble_geometry_space), the neo-Hookean
  one or a cause's: one column of deflections over the grid in the metadata; the
  grid, the ray specification, the cause and its nodes, and the rays that stopped
  early must be equal.

In both, the pressures must be the same and every deflection equal within
``rtol`` relative (|a - b| <= rtol * max(|a|, |b|)), NaN (beyond the last
converged pressure) at the same places.  Prints one line per database and exits
1 on any difference, 2 on a missing or unreadable database.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq

METADATA_KEY = b"skinsuction"  # skinsuction.space.METADATA_KEY
DEFAULT_GLOBS = ("results/simulated_space/*.parquet", "results/simulated_space/scale_free/*.parquet")


def read(path: Path):
    table = pq.read_table(path)
    raw = (table.schema.metadata or {}).get(METADATA_KEY)
    return table.to_pandas(), (json.loads(raw) if raw else {})


def rel_diff(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    scale = np.maximum(np.abs(a), np.abs(b))
    diff = np.abs(a - b)
    return np.divide(diff, scale, out=np.zeros_like(diff), where=scale > 0)


def compare_values(a, b, rtol, problems):
    """Deflections: NaN at the same places, finite ones within rtol; the largest rel. diff."""
    a = np.asarray(a, float)
    b = np.asarray(b, float)
    nan_a, nan_b = np.isnan(a), np.isnan(b)
    if (nan_a != nan_b).any():
        problems.append(f"NaN deflections differ at {int((nan_a != nan_b).sum())} rows")
    ok = ~nan_a & ~nan_b
    rd = rel_diff(a[ok], b[ok])
    worst = float(rd.max()) if rd.size else 0.0
    if worst > rtol:
        problems.append(f"{int((rd > rtol).sum())} deflections differ by more than {rtol:g} "
                        f"relative (largest {worst:.3g})")
    return worst, int(nan_a.sum())


def compare_grid(fa, fb, rtol):
    problems = []
    keys = ["point_id", "pressure_mbar"]
    fa = fa.sort_values(keys, ignore_index=True)
    fb = fb.sort_values(keys, ignore_index=True)
    pa, pb = fa.drop_duplicates("point_id"), fb.drop_duplicates("point_id")
    ids_a, ids_b = set(pa["point_id"]), set(pb["point_id"])
    if ids_a != ids_b:
        problems.append(f"points differ: only in A {sorted(ids_a - ids_b)[:5]}, "
                        f"only in B {sorted(ids_b - ids_a)[:5]}")
        return problems, {}
    conv_a = set(pa.loc[pa["converged"].astype(bool), "point_id"])
    conv_b = set(pb.loc[pb["converged"].astype(bool), "point_id"])
    if conv_a != conv_b:
        problems.append(f"converged points differ: only in A {sorted(conv_a - conv_b)}, "
                        f"only in B {sorted(conv_b - conv_a)}")
    last_a = pa.set_index("point_id")["last_converged_mbar"].sort_index()
    last_b = pb.set_index("point_id")["last_converged_mbar"].sort_index()
    if not np.array_equal(last_a.to_numpy(float), last_b.to_numpy(float), equal_nan=True):
        problems.append("last_converged_mbar differs")
    if not fa[keys].equals(fb[keys]):
        problems.append("(point, pressure) rows differ")
        return problems, {}
    worst, n_nan = compare_values(fa["deflection_mm"], fb["deflection_mm"], rtol, problems)
    return problems, {"kind": "grid", "units": "points", "n": len(ids_a),
                      "converged": len(conv_a & conv_b), "nan": n_nan, "worst": worst,
                      "values": len(fa)}


def ray_converged(meta, side, problems):
    rays = meta.get("rays")
    if not isinstance(rays, dict) or not rays:
        problems.append(f"{side}: no per-ray solver record in the metadata")
        return {}
    return {rid: bool(info.get("converged", False)) for rid, info in rays.items()}


def compare_rays(fa, fb, meta_a, meta_b, rtol):
    problems = []
    keys = ["probe_mm", "ratio", "coordinate", "pressure_mbar"]
    fa = fa.sort_values(keys, ignore_index=True)
    fb = fb.sort_values(keys, ignore_index=True)
    ka = fa[keys].to_numpy(float)
    kb = fb[keys].to_numpy(float)
    if ka.shape != kb.shape or not np.array_equal(ka, kb, equal_nan=True):
        problems.append("(probe, ratio, coordinate, pressure) rows differ")
        return problems, {}
    conv_a = ray_converged(meta_a, "A", problems)
    conv_b = ray_converged(meta_b, "B", problems)
    if set(conv_a) != set(conv_b):
        problems.append(f"rays differ: only in A {sorted(set(conv_a) - set(conv_b))[:5]}, "
                        f"only in B {sorted(set(conv_b) - set(conv_a))[:5]}")
    differ = sorted(r for r in set(conv_a) & set(conv_b) if conv_a[r] != conv_b[r])
    if differ:
        problems.append(f"converged rays differ: {differ}")
    worst, n_nan = compare_values(fa["deflection_mm"], fb["deflection_mm"], rtol, problems)
    n_rays = len(fa.drop_duplicates(keys[:3]))
    return problems, {"kind": "rays", "units": "rays", "n": n_rays,
                      "converged": sum(conv_a[r] and conv_b.get(r, False) for r in conv_a),
                      "nan": n_nan, "worst": worst, "values": len(fa)}


def compare_geometry(fa, fb, meta_a, meta_b, rtol):
    problems = []
    for key in ("grid", "spec", "cause", "stopped_early"):
        if meta_a.get(key) != meta_b.get(key):
            problems.append(f"{key} differs")
    if len(fa) != len(fb):
        problems.append(f"{len(fa)} and {len(fb)} deflections")
        return problems, {}
    worst, n_nan = compare_values(fa["deflection_mm"], fb["deflection_mm"], rtol, problems)
    n = int(meta_a.get("rays") or 0)
    return problems, {"kind": "geom", "units": "rays", "n": n,
                      "converged": n - len(meta_a.get("stopped_early") or {}),
                      "nan": n_nan, "worst": worst, "values": len(fa)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run_a", type=Path)
    ap.add_argument("run_b", type=Path)
    ap.add_argument("databases", nargs="*")
    ap.add_argument("--rtol", type=float, default=1e-9)
    args = ap.parse_args(argv)

    names = args.databases or sorted(
        {str(p.relative_to(run)) for run in (args.run_a, args.run_b)
         for g in DEFAULT_GLOBS for p in run.glob(g)})
    if not names:
        print("compare_runs: no database to compare", file=sys.stderr)
        return 2

    print(f"A = {args.run_a}\nB = {args.run_b}\nrtol = {args.rtol:g}")
    header = f"{'database':<56} {'kind':<5} {'items':>6} {'conv.both':>9} {'values':>7} " \
             f"{'NaN':>5} {'max rel diff':>12}  result"
    print(header)
    print("-" * len(header))
    status = 0
    for name in names:
        pa, pb = args.run_a / name, args.run_b / name
        missing = [str(p) for p in (pa, pb) if not p.is_file()]
        if missing:
            print(f"{name:<56} missing: {', '.join(missing)}")
            status = max(status, 2)
            continue
        try:
            (fa, ma), (fb, mb) = read(pa), read(pb)
        except Exception as err:  # pyarrow raises many types for a bad file
            print(f"{name:<56} unreadable: {type(err).__name__}: {err}")
            status = max(status, 2)
            continue
        if "point_id" in fa.columns and "point_id" in fb.columns:
            problems, s = compare_grid(fa, fb, args.rtol)
        elif {"ratio", "coordinate"} <= set(fa.columns) & set(fb.columns):
            problems, s = compare_rays(fa, fb, ma, mb, args.rtol)
        elif "grid" in ma and "grid" in mb:
            problems, s = compare_geometry(fa, fb, ma, mb, args.rtol)
        else:
            print(f"{name:<56} not a simulated space (columns {list(fa.columns)[:6]})")
            status = max(status, 2)
            continue
        if s:
            print(f"{name:<56} {s['kind']:<5} {s['n']:>6} {s['converged']:>9} {s['values']:>7} "
                  f"{s['nan']:>5} {s['worst']:>12.3g}  {'DIFFERENT' if problems else 'equal'}")
        else:
            print(f"{name:<56} DIFFERENT")
        for p in problems:
            print(f"    {p}")
        if problems:
            status = max(status, 1)
    print("the runs' databases are equal" if status == 0 else "the runs' databases DIFFER")
    return status


if __name__ == "__main__":
    sys.exit(main())
