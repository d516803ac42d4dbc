"""CPU cost of the scale-free space's FE rays: a baseline commit against the working tree
(prints figures; asserts nothing).

Builds the 768 rays of ``scale_free_space`` in config/config.yaml as the workflow
does, takes half of ``--rays`` from the corners of the space (smallest and largest
X1h/X1d, thickest and thinnest dermis, highest X2d/X1d and pre-stretch, both
probes) and half at random (``--seed``) from the rest, and runs each with
``compute_ray`` in child processes, one thread each, for the source of
``--baseline`` (a temporary git worktree) and for the working tree, alternately
batch by batch. Only ``time.process_time()`` around each ``compute_ray`` counts.

Prints per ray CPU-s old/new, Newton iterations (all solves), the fallback kept,
the last converged pressure and the largest difference of the two curves (% of
the new curve's max |M|, and point-wise at M > 0); then total CPU-s (the
headline), fallback solves and early stops per 100 rays, the rays the new
version covers less far, and the curve differences where both kept the same
element and where the splice moved.

    python benchmarks/ray_speed.py [--rays 40] [--seed 0] [--quick] [--batch 4]
        [--workers 1] [--baseline db7a382] [--out benchmarks/out/ray_speed.csv]
"""

from __future__ import annotations

import argparse
import inspect
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
TAG = "@ray_speed "  # prefix of the children's result lines
THREADS = {k: "1" for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
                            "NUMEXPR_NUM_THREADS", "VECLIB_MAXIMUM_THREADS")}
ABBR = {"neo_hookean": "NH", "strain_stiffening": "X2d", "dermis_thickness": "td",
        "pre_tension": "lam0"}
#: (model, index of X1h/X1d node, index of the cause's node): the corners of the space,
#: each taken under one probe first and, past ten, under the other
EXTREMES = [("neo_hookean", 0, None), ("strain_stiffening", -1, -1),
            ("dermis_thickness", 0, -1), ("pre_tension", 0, -1), ("neo_hookean", -1, None),
            ("strain_stiffening", 0, -1), ("dermis_thickness", -1, 0), ("pre_tension", -1, -1),
            ("dermis_thickness", 0, 0), ("dermis_thickness", -1, -1)]


def child():
    """Run the rays of one batch on whatever ``skinsuction`` PYTHONPATH gives."""
    job = json.load(sys.stdin)
    import felupe, pandas, scipy.sparse.linalg  # noqa: E401, F401  first-use costs untimed
    import skinsuction
    import skinsuction.model as model
    from skinsuction.space._ray_solve import compute_ray

    known = set(model.MeshSettings.__dataclass_fields__) | {"iterations_per_step"}
    dropped = sorted({k for m in [job["mesh"], *job["fallback"]] for k in m} - known)
    mesh = {k: v for k, v in job["mesh"].items() if k in known}
    fallback = [{k: v for k, v in f.items() if k in known} for f in job["fallback"]]
    real, calls = model.simulate, []

    def counted(*args, **kw):  # the ray's solves: main, onset, fallbacks (iteration budget)
        curve = real(*args, **kw)
        calls.append(("iteration_budget" in kw, int(curve.newton_iterations or 0)))
        return curve

    real(x1d=0.05, x1h=1e-3, probe_mm=2, pressures_mbar=[0.0, 5.0, 10.0], mesh=mesh)  # warm-up
    model.simulate = counted  # read at call time by the fallback chain and the onset solve
    print(TAG + json.dumps({"file": skinsuction.__file__, "dropped": dropped}), flush=True)
    for rid in job["rays"]:
        calls.clear()
        start = time.process_time()
        # before the onset was folded into the ray's one solve, it was a separate solve
        extra = (job["onset"],) if "onset_mbar" in inspect.signature(compute_ray).parameters else ()
        _, frame, info = compute_ray(rid, job["pressures"], mesh, fallback, *extra)
        cpu = time.process_time() - start
        print(TAG + json.dumps({
            "ray_id": rid, "cpu_s": cpu, "newton_kept": info["newton_iterations"],
            "newton_all": sum(n for _, n in calls), "solves": len(calls),
            "fallback_solves": sum(fb for fb, _ in calls), "mesh_fallback": info["mesh_fallback"],
            "converged": info["converged"], "last_mbar": info["last_converged_mbar"],
            "deflection_mm": frame["deflection_mm"].astype(float).tolist()}), flush=True)


def all_rays(config_path):
    """The workflow's rays: ``{ray_id: (model, probe, ratio, coordinate)}`` and the job."""
    import yaml

    from skinsuction.space import RaySpec, ray_bundles, rays_of, registry_from_config

    cfg = yaml.safe_load(Path(config_path).read_text())
    sf = cfg["scale_free_space"]
    causes = registry_from_config(sf["causes"])
    spec = RaySpec.from_config(sf, cfg.get("mesh"), cfg.get("mesh_fallback"))
    where = {}
    for name, cause in {"neo_hookean": None, **causes}.items():
        for ray in rays_of(spec, cause):
            where.setdefault(ray["ray_id"], (name, ray["probe_mm"], ray["ratio"],
                                             ray["coordinate"]))
    rays = {rid: where[rid] for ids in ray_bundles(spec, causes).values() for rid in ids}
    job = {"pressures": list(spec.pressures_mbar), "onset": list(spec.onset_mbar),
           "mesh": dict(spec.mesh), "fallback": [dict(f) for f in spec.fallback]}
    return rays, spec, causes, job


def pick(rays, spec, causes, n, seed):
    """``n // 2`` corners of the space (as listed in EXTREMES), the rest at random."""
    index = {(m, p, r, None if m == "neo_hookean" else c): rid
             for rid, (m, p, r, c) in rays.items()}
    probes = sorted(spec.probes_mm, reverse=True)
    corners = []
    for turn in range(2):
        for i, (m, ir, ic) in enumerate(EXTREMES):
            probe = probes[(i + turn) % len(probes)]
            c = None if ic is None else causes[m].nodes[ic]
            corners.append(index[(m, probe, spec.ratio_nodes[ir], c)])
    n_ext = min(n // 2, len(corners))
    rest = [rid for rid in rays if rid not in set(corners)]
    order = np.random.default_rng(seed).permutation(len(rest))[: n - n_ext]
    return [(rid, "extreme") for rid in corners[:n_ext]] + [(rest[i], "random") for i in order]


def run_batch(src, rays, job):
    env = {**os.environ, **THREADS, "PYTHONPATH": str(src)}
    proc = subprocess.run([sys.executable, str(Path(__file__).resolve()), "--child"],
                          input=json.dumps({**job, "rays": rays}), env=env, text=True,
                          capture_output=True)
    lines = [json.loads(s[len(TAG):]) for s in proc.stdout.splitlines() if s.startswith(TAG)]
    if proc.returncode or len(lines) != len(rays) + 1:
        print(f"warning: a child on {src} ended with {proc.returncode}:\n"
              + proc.stderr[-2000:], file=sys.stderr)
    head = lines[0] if lines else {"file": "?", "dropped": []}
    return head, {d["ray_id"]: d for d in lines[1:]}


def curve_diff(old, new):
    """Largest |M_old - M_new| where both are finite: % of max |M_new|, point-wise %."""
    mo, mn = np.asarray(old, dtype=float), np.asarray(new, dtype=float)
    both = np.isfinite(mo) & np.isfinite(mn)
    if not both.any():
        return np.nan, np.nan
    d = np.abs(mo - mn)
    pos = both & (mn > 0)
    point = 100 * np.max(d[pos] / mn[pos]) if pos.any() else np.nan
    return 100 * d[both].max() / np.nanmax(np.abs(mn[both])), point


def stats(values):
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    return "n/a" if not v.size else f"median {np.median(v):.3g}, 95th pct {np.percentile(v, 95):.3g}, max {v.max():.3g}"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rays", type=int, default=40, help="rays, half of them corners")
    ap.add_argument("--quick", action="store_true", help="6 rays: a smoke test")
    ap.add_argument("--seed", type=int, default=0, help="seed of the random rays")
    ap.add_argument("--batch", type=int, default=4, help="rays per child process")
    ap.add_argument("--workers", type=int, default=1, help="batches run at once")
    ap.add_argument("--baseline", default="db7a382", help="commit of the old version")
    ap.add_argument("--config", default=str(ROOT / "config" / "config.yaml"))
    ap.add_argument("--out", help="CSV of the per-ray table")
    args = ap.parse_args()
    n = 6 if args.quick else args.rays

    rays, spec, causes, job = all_rays(args.config)
    chosen = pick(rays, spec, causes, n, args.seed)
    git = ["git", "-C", str(ROOT)]
    head, dirty = (subprocess.run([*git, *a], capture_output=True, text=True).stdout.strip()
                   for a in (["rev-parse", "--short", "HEAD"], ["status", "--porcelain", "src"]))
    print(f"{len(rays)} rays in the space; {n} run ({sum(c == 'extreme' for _, c in chosen)} "
          f"extreme, seed {args.seed}); old = {args.baseline}, new = working tree "
          f"({head}{' + uncommitted src' if dirty else ''}); batches of {args.batch}, "
          f"{args.workers} worker(s)")
    tmp = Path(tempfile.mkdtemp(prefix="ray-speed-"))
    tree = tmp / "baseline"
    subprocess.run([*git, "worktree", "add", "--quiet", "--detach", str(tree), args.baseline],
                   check=True)
    old, new, heads = {}, {}, {}
    try:
        batches = [chosen[i:i + args.batch] for i in range(0, n, args.batch)]

        def one(k):  # the two versions back to back, who goes first alternating
            ids = [rid for rid, _ in batches[k]]
            order = [("old", tree / "src"), ("new", ROOT / "src")][:: 1 if k % 2 == 0 else -1]
            for name, src in order:
                h, out = run_batch(src, ids, job)
                heads.setdefault(name, h)
                (old if name == "old" else new).update(out)
            return k

        start = time.perf_counter()
        with ThreadPoolExecutor(max(1, args.workers)) as pool:
            for k in pool.map(one, range(len(batches))):
                print(f"  batch {k + 1}/{len(batches)} done, {time.perf_counter() - start:.0f} s"
                      " wall", file=sys.stderr, flush=True)
    finally:
        subprocess.run([*git, "worktree", "remove", "--force", str(tree)], check=False)
        shutil.rmtree(tmp, ignore_errors=True)
    for name in ("old", "new"):
        h = heads.get(name, {})
        print(f"{name}: skinsuction from {h.get('file')}"
              + (f"; mesh keys it lacks, dropped: {h['dropped']}" if h.get("dropped") else ""))

    rows, nan = [], {"cpu_s": np.nan, "newton_all": np.nan, "newton_kept": np.nan,
                     "mesh_fallback": -1, "fallback_solves": np.nan, "solves": np.nan,
                     "converged": False, "last_mbar": np.nan, "deflection_mm": []}
    for rid, cls in chosen:
        o, w = old.get(rid, nan), new.get(rid, nan)
        m, probe, ratio, c = rays[rid]
        short = f"{ABBR.get(m, m)} p{probe:g} r{ratio:.3g}" + ("" if m == "neo_hookean"
                                                              else f" {c:g}")
        dmax, dpt = curve_diff(o["deflection_mm"], w["deflection_mm"]) \
            if len(o["deflection_mm"]) == len(w["deflection_mm"]) else (np.nan, np.nan)
        row = {"ray": short, "class": cls, "model": m, "ray_id": rid}
        for tag, d in (("old", o), ("new", w)):
            row.update({f"{k}_{tag}": d[k] for k in nan if k != "deflection_mm"})
        row.update(ratio=row["cpu_s_old"] / row["cpu_s_new"], dM_pct_max=dmax, dM_pct_point=dpt)
        rows.append(row)

    print(f"\n{'ray':<24} {'class':<7} {'CPU-s old':>9} {'new':>7} {'ratio':>6} "
          f"{'Newton old':>10} {'new':>5} {'fb o/n':>6} {'last mbar o/n':>14} "
          f"{'dM % max':>8} {'dM % pt':>8}")
    for r in rows:
        print(f"{r['ray']:<24} {r['class']:<7} {r['cpu_s_old']:>9.2f} {r['cpu_s_new']:>7.2f} "
              f"{r['ratio']:>6.2f} {r['newton_all_old']:>10.0f} {r['newton_all_new']:>5.0f} "
              f"{r['mesh_fallback_old']:>3d}/{r['mesh_fallback_new']:<2d} "
              f"{r['last_mbar_old']:>7.4g}/{r['last_mbar_new']:<6.4g} "
              f"{r['dM_pct_max']:>8.2g} {r['dM_pct_point']:>8.2g}")

    import pandas as pd

    t = pd.DataFrame(rows)
    tot_o, tot_n = t["cpu_s_old"].sum(), t["cpu_s_new"].sum()
    per100 = lambda s: 100 * s.mean()  # noqa: E731
    print(f"\nCPU-s in all: old {tot_o:.1f}, new {tot_n:.1f}: {tot_o / tot_n:.2f} x fewer CPU-s "
          f"per ray (median per-ray ratio {t['ratio'].median():.2f})")
    for cls, g in t.groupby("class"):
        print(f"  {cls:<7} rays: old {g['cpu_s_old'].sum():.1f}, new {g['cpu_s_new'].sum():.1f}"
              f" CPU-s ({g['cpu_s_old'].sum() / g['cpu_s_new'].sum():.2f} x)")
    print(f"Newton iterations per ray (all solves, mean): old {t['newton_all_old'].mean():.0f},"
          f" new {t['newton_all_new'].mean():.0f}")
    print(f"fallback solves per 100 rays: old {per100(t['fallback_solves_old']):.0f}, "
          f"new {per100(t['fallback_solves_new']):.0f}")
    print(f"rays that stop early per 100 rays: old {per100(~t['converged_old']):.0f}, "
          f"new {per100(~t['converged_new']):.0f}")
    lo = t[t["last_mbar_new"].fillna(-1) < t["last_mbar_old"].fillna(-1) - 1e-9]
    print(f"rays whose last converged pressure is lower in the new version: {len(lo)}")
    for r in lo.itertuples():
        print(f"  {r.ray} ({r.ray_id}): {r.last_mbar_old:g} -> {r.last_mbar_new:g} mbar")
    same = t["mesh_fallback_old"] == t["mesh_fallback_new"]
    for label, g in (("same element kept", t[same]), ("the splice moved", t[~same])):
        print(f"curve difference, {label} ({len(g)} rays): % of max|M| "
              f"{stats(g['dM_pct_max'])}; point-wise % {stats(g['dM_pct_point'])}")
    if args.out:
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        t.to_csv(args.out, index=False)
        print(f"per-ray table: {args.out}")


if __name__ == "__main__":
    child() if sys.argv[1:] == ["--child"] else main()
