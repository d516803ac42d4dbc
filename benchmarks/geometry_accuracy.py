"""Accuracy of the neo-Hookean space at any probe and layers, against direct FE runs.

    python benchmarks/geometry_accuracy.py [--space-dir DIR] [--geometries 30]
        [--per-geometry 4] [--seed 0] [--workers 2] [--cache DIR]
        [--geometry-space FILE | --no-geometry-space] [--side-by-side]
        [--aperture 2,8] [--t-d 0.5,2.5] [--t-h 0.5,10]

Draws random geometries (the aperture uniform in 2-8 mm, t_d uniform in 0.5-2.5
mm, t_h log-uniform in 0.5-10 mm; narrower ranges with --aperture, --t-d, --t-h, e.g.
the thin corner), solves their neo-Hookean rays on demand (as
`identify` and `diagnose` do, skinsuction.space.OnDemandRays), then at random
points of each (X1h/X1d log-uniform over the ratio nodes, X1d log-uniform in
0.005-0.15 MPa raised to the load reach, a protocol to 100, 300 or 500 mbar)
compares the interpolated space with a direct FE run at every pressure, as
benchmarks/scale_free_accuracy.py does for the precomputed probes. Prints the
percentiles of the relative error overall and per aperture band. Asserts nothing.

The rays of a geometry are read off the geometry space (the default,
skinsuction.space.GeometrySpace) where it holds them; --no-geometry-space solves
them all. --side-by-side does both in one run, against the same direct FE runs,
and prints both tables with the CPU a geometry's rays cost each way. The rays read
are also read along the load with the first load axis (cubic Lagrange of M in q,
benchmarks/_load_before.py), against the same FE runs.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd
from _pool import mm_range

_CTX = {}


def _init(space_dir, cache, geometry, side_by_side, tolerance):
    from skinsuction.space import BASELINE, OnDemandRays, read_ray_spaces

    base = read_ray_spaces(space_dir)[BASELINE]
    _CTX.update(base=base, solver=OnDemandRays(base.spec, cache_dir=cache, geometry=geometry,
                                               progress=None, tolerance=tolerance))
    if side_by_side:
        _CTX["solved"] = OnDemandRays(base.spec, cache_dir=cache, geometry=None, progress=None)
    if geometry is not None:  # the grid alone, every ray read whatever its error estimate
        _CTX["raw"] = OnDemandRays(base.spec, cache_dir=cache, geometry=geometry, progress=None,
                                   tolerance=math.inf)


def _run(job):
    from skinsuction.evaluation import AccuracyPoint, compare_point
    from skinsuction.space import BASELINE, Geometry, spaces_at

    from _load_before import read_m_in_q

    (probe, t_d, t_h), points = job
    t0 = time.process_time()
    g = Geometry(t_d, t_h, given=("t_d", "t_h"))
    before = _CTX["solver"].interpolated
    spaces, notes = spaces_at({BASELINE: _CTX["base"]}, [probe], g, _CTX["solver"])
    rays_cpu = time.process_time() - t0
    source = "geometry space" if _CTX["solver"].interpolated > before else "solved"
    solved_rays = sum(int(n.split("(")[1].split(" solved")[0]) for n in notes
                      if "solved on demand where its error estimate" in n)
    solved = None
    if "solved" in _CTX:
        t0 = time.process_time()
        solved = spaces_at({BASELINE: _CTX["base"]}, [probe], g, _CTX["solved"])[0][BASELINE]
        solved_cpu = time.process_time() - t0
    raw = None
    if "raw" in _CTX and _CTX["raw"].geometry.grid.covers(2 * t_d / probe, 2 * t_h / probe):
        raw = spaces_at({BASELINE: _CTX["base"]}, [probe], g, _CTX["raw"])[0][BASELINE]
    out = []
    for (x1d, ratio, p_max, p_step) in points:
        pt = AccuracyPoint(BASELINE, probe, x1d, ratio, math.nan, p_max, p_step, t_d, t_h)
        rec = compare_point(spaces[BASELINE], pt)
        rec["before_mm"] = read_m_in_q(spaces[BASELINE], pt, rec["pressure_mbar"])
        if raw is not None:
            rec["raw_mm"] = _read_at(raw, pt, rec["pressure_mbar"])
        rec["rays_cpu_s"] = rays_cpu
        rec["rays_source"] = source
        rec["rays_solved_of_16"] = solved_rays if source == "geometry space" else 16
        if solved is not None:
            rec["solved_mm"] = _read_at(solved, pt, rec["pressure_mbar"])
            rec["solved_rays_cpu_s"] = solved_cpu
        out.append(rec)
    return out


def _read_at(space, pt, pressures):
    """The space's curve of the point at the pressures compared."""
    from skinsuction.evaluation._accuracy import interpolant

    if not pressures:
        return []
    f = interpolant(space, pt.probe_mm, np.asarray(pressures, float))
    return f([[math.log10(pt.x1d), math.log10(pt.ratio)]])[0].tolist()


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--space-dir", default="results/simulated_space/scale_free")
    ap.add_argument("--geometries", type=int, default=30)
    ap.add_argument("--per-geometry", type=int, default=4)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--cache", default="benchmarks/out/on_demand")
    ap.add_argument("--out", default="benchmarks/out/geometry_accuracy.csv")
    ap.add_argument("--geometry-space", default="auto",
                    help="geometry space file (default: the workflow's build, else the shipped)")
    ap.add_argument("--no-geometry-space", action="store_true",
                    help="solve every geometry's rays (today's rays on demand)")
    ap.add_argument("--tolerance", type=float, default=1e-2,
                    help="error estimate above which a ray is solved (inf: never)")
    ap.add_argument("--side-by-side", action="store_true",
                    help="also solve the rays and compare both with the same FE runs")
    for key, default in (("aperture", "2,8"), ("t-d", "0.5,2.5"), ("t-h", "0.5,10")):
        ap.add_argument(f"--{key}", default=default, type=mm_range,
                        help=f"range drawn from, mm (default {default})")
    args = ap.parse_args(argv)
    geometry = None if args.no_geometry_space else args.geometry_space

    from skinsuction.evaluation import PROTOCOLS
    from skinsuction.space import BASELINE, read_ray_spaces

    spec = read_ray_spaces(args.space_dir)[BASELINE].spec
    rng = np.random.default_rng(args.seed)
    lr = np.log10(spec.ratio_nodes)
    jobs = []
    for _ in range(args.geometries):
        geo = (round(float(rng.uniform(*args.aperture)), 2),
               round(float(rng.uniform(*args.t_d)), 2),
               round(float(10 ** rng.uniform(*np.log10(args.t_h))), 2))
        pts = []
        for _ in range(args.per_geometry):
            p_max, p_step = PROTOCOLS[rng.integers(len(PROTOCOLS))]
            lo = max(0.005, p_max / spec.load_max)
            x1d = 10 ** rng.uniform(math.log10(lo), math.log10(max(lo * 1.0001, 0.15)))
            pts.append((float(x1d), float(10 ** rng.uniform(lr[0], lr[-1])), p_max, p_step))
        jobs.append((geo, pts))
    t0 = time.perf_counter()
    with ProcessPoolExecutor(args.workers, initializer=_init,
                             initargs=(args.space_dir, args.cache, geometry,
                                       args.side_by_side, args.tolerance)) as pool:
        records = [r for rs in pool.map(_run, jobs) for r in rs]
    wall = time.perf_counter() - t0
    rows = []
    for r in records:
        solved = r.get("solved_mm") or [math.nan] * len(r["fe_mm"])
        raw = r.get("raw_mm") or [math.nan] * len(r["fe_mm"])
        for p, fe, sp, so, ra, be in zip(r["pressure_mbar"], r["fe_mm"], r["space_mm"], solved,
                                         raw, r["before_mm"]):
            rows.append({k: r[k] for k in ("probe_mm", "t_d", "t_h", "x1d", "ratio", "p_max",
                                           "rays_source", "rays_solved_of_16")}
                        | {"pressure_mbar": p, "fe_mm": fe, "space_mm": sp, "solved_mm": so,
                           "raw_mm": ra, "before_mm": be})
    per_p = pd.DataFrame(rows)
    per_p["relative_error"] = (per_p["space_mm"] - per_p["fe_mm"]).abs() / per_p["fe_mm"].abs()
    for k in ("solved", "raw", "before"):
        per_p[f"{k}_relative_error"] = ((per_p[f"{k}_mm"] - per_p["fe_mm"]).abs()
                                        / per_p["fe_mm"].abs())
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    per_p.to_csv(out, index=False)
    pts = pd.DataFrame([{k: v for k, v in r.items() if not isinstance(v, list)}
                        for r in records])
    pts.to_csv(out.with_name(out.stem + "_points.csv"), index=False)
    print(f"{args.geometries} geometries x {args.per_geometry} points ({args.seed=}), "
          f"{len(per_p)} pressures compared; {wall:.0f} s wall on {args.workers} workers; "
          f"rays {pts.groupby(['probe_mm', 't_d', 't_h'])['rays_cpu_s'].first().median():.2f}"
          " CPU-s per geometry (median); sources: "
          f"{pts.groupby(['probe_mm', 't_d', 't_h'])['rays_source'].first().value_counts().to_dict()}")
    geo = pts.groupby(["probe_mm", "t_d", "t_h"])["rays_solved_of_16"].first()
    print(f"rays solved where the error estimate exceeded {args.tolerance:g}: "
          f"{int(geo.sum())} of {16 * len(geo)} ({100 * geo.sum() / (16 * len(geo)):.1f} %); "
          f"geometries with none solved: {int((geo == 0).sum())} of {len(geo)}")
    if args.side_by_side:
        print(f"rays solved on demand: {pts.groupby(['probe_mm', 't_d', 't_h'])['solved_rays_cpu_s'].first().median():.1f}"
              " CPU-s per geometry (median)")
    print(f"pressures beyond the space's coverage where FE has a value: "
          f"{int(pts['n_fe_only'].sum())}")

    def stats(v):
        v = np.asarray(v, float)
        return (f"median {100 * np.median(v):.3f} %, 95th percentile "
                f"{100 * np.percentile(v, 95):.3f} %, max {100 * v.max():.3f} %")

    columns = [("relative_error", "rays read"), ("raw_relative_error", "grid alone"),
               ("before_relative_error", "rays read, the first load axis (M in q)")]
    if args.side_by_side:
        columns.append(("solved_relative_error", "rays solved"))
    bands = pd.cut(per_p["probe_mm"], [2, 3, 5, 7, 8.0001], right=False,
                   labels=["2-3 mm", "3-5 mm", "5-7 mm", "7-8 mm"])
    for col, label in columns:
        sel = per_p[per_p[col].notna()]
        print(f"{label}: [all] {len(sel)} pressures: {stats(sel[col])}")
        for band, g in sel.groupby(bands, observed=True):
            print(f"{label}: [{band}] {len(g)} pressures: {stats(g[col])}")
    print(f"written: {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
