"""A cause's rays read off its geometry space, against the same rays solved by FE.

    python benchmarks/cause_geometry_accuracy.py --cause strain_stiffening
        [--geometries 24] [--ratios 3] [--seed 0] [--workers 2] [--cache DIR]
        [--tolerance 0.01] [--space-dir DIR] [--aperture 2,8] [--t-d 0.5,2.5] [--t-h 0.5,10]

Draws random geometries (aperture uniform in 2-8 mm, t_d uniform in 0.5-2.5 mm,
t_h log-uniform in 0.5-10 mm; narrower ranges with --aperture, --t-d, --t-h) and, at
each, random X1h/X1d nodes; reads the cause's rays there at every node of the cause
(skinsuction.space.OnDemandRays, the geometry spaces beside --space-dir: by default
the workflow's build, else the shipped one; a copy, not a link, since a link is
followed to its target's folder) and solves the same rays directly (geometry=None, a
cache of their own). Prints the largest relative error of M along each ray (over the loads where
both exist): percentiles overall, per aperture band and per cause node, for the
rays read (the default tolerance) and for the grid alone (every ray read whatever
its error estimate); then the error at every load read, pooled (the statistic of
the neo-Hookean tables); the rays that fell back to FE (an error estimate over the
tolerance, or a geometry outside the grid), and the CPU of both ways.
Last, whether the error estimate can be trusted: per band of t_h/a and of t_d/a, the grid's
estimate of each ray against its error (|log M| against FE, loads up to M = 1.5 mm,
what a fit reads): how often the estimate is under the error, and their ratio.
Asserts nothing.
"""

from __future__ import annotations

import argparse
import math
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd
from _pool import mm_range

_CTX = {}
CAP_MM = 1.5  # the estimate is weighed over the loads up to this deflection


def _init(cause_name, cache, tolerance, space_dir):
    from skinsuction.space import BASELINE, OnDemandRays, geometry_file_for, read_ray_spaces

    spaces = read_ray_spaces(space_dir)
    spec = spaces[BASELINE].spec
    geometry = geometry_file_for(space_dir)  # its causes' spaces lie beside it
    _CTX.update(cause=spaces[cause_name].cause,
                read=OnDemandRays(spec, cache_dir=cache, progress=None, tolerance=tolerance,
                                  geometry=geometry),
                raw=OnDemandRays(spec, cache_dir=cache, progress=None, tolerance=math.inf,
                                 geometry=geometry),
                solved=OnDemandRays(spec, cache_dir=cache, geometry=None, progress=None))
    if _CTX["read"].cause_geometry(_CTX["cause"]) is None:
        raise SystemExit(f"no geometry space of {cause_name} beside the neo-Hookean one")


def _run(job):
    probe, t_d, t_h, nodes = job
    layers = {"dermis.thickness": t_d, "hypodermis.thickness": t_h}
    cause = _CTX["cause"]
    t0 = time.process_time()
    read, info = _CTX["read"].rays(probe, layers, cause, ratio_nodes=nodes)
    read_cpu = time.process_time() - t0
    raw, _ = _CTX["raw"].rays(probe, layers, cause, ratio_nodes=nodes)
    t0 = time.process_time()
    solved, _ = _CTX["solved"].rays(probe, layers, cause, ratio_nodes=nodes)
    solved_cpu = time.process_time() - t0
    space, a = _CTX["read"].cause_geometry(cause), probe / 2
    inside = space.grid.covers(t_d / a, t_h / a)
    out = []
    for k, r in enumerate(nodes):
        for j, c in enumerate(cause.nodes):
            if c == cause.neutral:
                continue
            ok = np.isfinite(read[k, j]) & np.isfinite(solved[k, j]) & (solved[k, j] > 0)
            n_fe = int(np.isfinite(solved[k, j]).sum())
            e = np.abs(read[k, j, ok] / solved[k, j, ok] - 1)
            okr = np.isfinite(raw[k, j]) & np.isfinite(solved[k, j]) & (solved[k, j] > 0)
            er = np.abs(raw[k, j, okr] / solved[k, j, okr] - 1)
            low = okr & (solved[k, j] <= CAP_MM)  # the loads a fit reads
            est = (space.rays(2.0, t_d / a, t_h / a, [r], c, deflection_cap=CAP_MM / a)[1]
                   ["error_estimate"][0] if inside else math.nan)
            el = np.abs(np.log(raw[k, j, low] / solved[k, j, low]))
            out.append({"probe_mm": probe, "t_d": t_d, "t_h": t_h, "ratio": r, "node": c,
                        "load_errors": e.tolist(),
                        "max_error": float(e.max()) if e.size else math.nan,
                        "raw_max_error": float(er.max()) if er.size else math.nan,
                        "estimate": float(est),
                        "error_to_cap": float(el.max()) if el.size else math.nan,
                        "th_a": t_h / a,
                        "loads_read": int(ok.sum()), "loads_fe": n_fe,
                        "rays_solved": info.get("rays_solved", 0),
                        "outside_grid": not inside,
                        "read_cpu_s": read_cpu, "solved_cpu_s": solved_cpu})
    return out


def _band(probe):
    for lo, hi in ((2, 3), (3, 5), (5, 7), (7, 8.01)):
        if lo <= probe < hi:
            return f"{lo}-{int(hi)} mm"
    return "?"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cause", default="strain_stiffening")
    ap.add_argument("--geometries", type=int, default=24)
    ap.add_argument("--ratios", type=int, default=3)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--cache", default="benchmarks/out/cause_geometry_cache")
    ap.add_argument("--tolerance", type=float, default=1e-2)
    ap.add_argument("--out", default="benchmarks/out/cause_geometry_accuracy.csv")
    ap.add_argument("--space-dir", default=None,
                    help="scale-free space (default: the workflow's build, else the shipped)")
    for key, default in (("aperture", "2,8"), ("t-d", "0.5,2.5"), ("t-h", "0.5,10")):
        ap.add_argument(f"--{key}", default=default, type=mm_range,
                        help=f"range drawn from, mm (default {default})")
    a = ap.parse_args(argv)
    from skinsuction.space import BASELINE, read_ray_spaces
    from skinsuction.space._shipped import default_space_dir

    space_dir = a.space_dir or default_space_dir()
    nodes = read_ray_spaces(space_dir)[BASELINE].spec.ratio_nodes
    rng = np.random.default_rng(a.seed)
    jobs = []
    for _ in range(a.geometries):
        probe = float(rng.uniform(*a.aperture))
        t_d, t_h = float(rng.uniform(*a.t_d)), float(np.exp(rng.uniform(*np.log(a.t_h))))
        pick = sorted(rng.choice(len(nodes), a.ratios, replace=False))
        jobs.append((round(probe, 3), round(t_d, 2), round(t_h, 2),
                     tuple(nodes[i] for i in pick)))
    w0 = time.time()
    with ProcessPoolExecutor(a.workers, initializer=_init,
                             initargs=(a.cause, a.cache, a.tolerance, space_dir)) as pool:
        rows = [r for out in pool.map(_run, jobs) for r in out]
    df = pd.DataFrame(rows)
    df["band"] = df["probe_mm"].map(_band)
    loads = df.pop("load_errors")
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)  # a fresh checkout has none
    df.to_csv(a.out, index=False)
    print(f"{a.cause}: {len(jobs)} geometries, {len(df)} rays, {time.time() - w0:.0f} s wall")

    def pct(x):
        x = x.dropna()
        return (f"{100 * np.percentile(x, 50):.3f} / {100 * np.percentile(x, 95):.3f} / "
                f"{100 * x.max():.3f} %")
    print("max relative error of M along a ray: median / 95th pct / max")
    print(f"  all       read {pct(df['max_error'])}   grid alone {pct(df['raw_max_error'])}")
    for band, g in df.groupby("band"):
        print(f"  {band:8s}  read {pct(g['max_error'])}   grid alone {pct(g['raw_max_error'])}"
              f"   ({len(g)} rays)")
    print("relative error of M at every load read (pooled, as the neo-Hookean tables): "
          "median / 95th pct / max")
    for band, g in [("all", df), *df.groupby("band")]:
        x = pd.Series(np.concatenate([np.asarray(v, float) for v in loads[g.index]]))
        print(f"  {band:8s}  {pct(x)}   ({x.size} loads)")
    for node, g in df.groupby("node"):
        print(f"  node {node:g}: read {pct(g['max_error'])}")
    per_geom = df.drop_duplicates(["probe_mm", "t_d", "t_h"])
    print(f"rays solved at the tolerance {a.tolerance:g}: {int(per_geom['rays_solved'].sum())} of "
          f"{len(df)}, and {int(df['outside_grid'].sum())} outside the grid; loads read "
          f"{int(df['loads_read'].sum())} of {int(df['loads_fe'].sum())} solved by FE")
    print(f"CPU per geometry (median): read {per_geom['read_cpu_s'].median():.3f} s, "
          f"solved {per_geom['solved_cpu_s'].median():.1f} s")
    print(f"the grid's error estimate against its error (loads up to M = {CAP_MM:g} mm): "
          "rays, estimate under the error, median estimate / error, error 95th pct")
    df["td_a"] = df["t_d"] / (df["probe_mm"] / 2)
    for axis, edges in (("th_a", [0, 0.09, 0.125, 0.2, 0.5, np.inf]),
                        ("td_a", [0, 0.1, 0.125, 0.15, 0.2, 0.5, np.inf])):
        bins = pd.cut(df[axis], edges)
        for band, g in df[df["error_to_cap"] > 0].groupby(bins, observed=True):
            ratio = g["estimate"] / g["error_to_cap"]
            print(f"  {axis.replace('_a', '/a').replace('t', 't_', 1)} {band}: {len(g)} rays, "
                  f"{int((ratio < 1).sum())} under, {ratio.median():.2f}, "
                  f"{100 * g['error_to_cap'].quantile(0.95):.2f} %")


if __name__ == "__main__":
    main()
