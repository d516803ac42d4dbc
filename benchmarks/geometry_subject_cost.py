"""Cost and results per new subject with measured layers: the geometry space against rays solved.

    python benchmarks/geometry_subject_cost.py [--subjects 6] [--diagnose 2] [--seed 0]
        [--workers 2] [--space-dir DIR]

Each subject is an FE virtual experiment (reference mesh, fixed bottom,
neo-Hookean, 0-100 mbar in 2 mbar steps, 1.5 µm noise) on layers drawn as
measured in vivo (t_d uniform in 0.5-2.5 mm, t_h log-uniform in 0.5-10 mm), the
2 + 6 mm or 4 + 8 mm probes, X1d log-uniform in 0.01-0.06 MPa, X1h/X1d in
0.003-0.3; the layers are given, the dermis with an sd of 0.1 mm. Each subject is
identified (weighted objective, 4 runs polished, 95 % intervals) twice, each
from an empty ray cache: with the rays read off the geometry space (solved only
where its error estimate exceeds the tolerance), and with every ray solved (the
reference, `--solve-rays`). The first --diagnose subjects are also diagnosed
both ways. Prints the CPU of each (median, max), how far the estimates differ in
units of their interval width, and whether the verdicts agree. Asserts nothing.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from _pool import run_rows

NOISE_MM = 1.5e-3
P = np.arange(0.0, 101.0, 2.0)
SD_MM = 0.1


def _data(i, seed, probes, t_d, t_h, x1d, ratio):
    from skinsuction.measured import MeasuredCurve, MeasuredData
    from skinsuction.model import Skin, simulate

    rng = np.random.default_rng(seed)
    curves = []
    for p in probes:
        c = simulate(Skin.two_layer(x1d, x1d * ratio, t_d=t_d, t_h=t_h), probe=p,
                     pressures_mbar=P)
        if not c.converged:
            return None
        m = np.asarray(c.deflection_mm) + rng.normal(0.0, NOISE_MM, P.size)
        m[0] = 0.0
        curves.append(MeasuredCurve(p, P, m))
    return MeasuredData(f"subject {i}", tuple(curves))


def _run(job):
    from skinsuction.diagnose._diagnose import Settings, diagnose
    from skinsuction.identify.measured_fit import identify_data
    from skinsuction.space import Geometry, OnDemandRays, load_space, read_ray_spaces

    i, seed, (probes, t_d, t_h, x1d, ratio), space_dir, do_diagnose = job
    data = _data(i, seed, probes, t_d, t_h, x1d, ratio)
    row = {"subject": i, "probes": "+".join(f"{p:g}" for p in probes), "t_d": t_d,
           "t_h": t_h, "x1d": x1d, "x1h": x1d * ratio}
    if data is None:
        return {**row, "error": "FE curve stopped before 100 mbar"}
    g = Geometry(t_d, t_h, given=("t_d", "t_h"), sd={"t_d": SD_MM})
    spaces = read_ray_spaces(space_dir)
    for mode, geometry in (("read", "auto"), ("solved", None)):
        with tempfile.TemporaryDirectory() as cache:
            solver = OnDemandRays(spaces["neo_hookean"].spec, cache_dir=cache, progress=None,
                                  geometry=geometry)
            space = load_space(space_dir, solve_on_demand=False)
            space.on_demand = solver
            t0 = time.process_time()
            r = identify_data(data, space, objective="weighted", repeats=4, seed=seed,
                              noise_um=1e3 * NOISE_MM, geometry=g)
            row[f"{mode}_identify_cpu_s"] = time.process_time() - t0
            row[f"{mode}_ray_sets_solved"] = solver.solved  # a probe's rays at one geometry
            for k, key in (("X1d", "x1d_mpa"), ("X1h", "x1h_mpa")):
                iv = (r["intervals"] or {}).get(k) or {}
                row[f"{mode}_{k}"] = r["estimate"][key]
                row[f"{mode}_{k}_lo"] = iv.get("lower", math.nan)
                row[f"{mode}_{k}_hi"] = iv.get("upper", math.nan)
            if do_diagnose:
                solver = OnDemandRays(spaces["neo_hookean"].spec, cache_dir=cache,
                                      progress=None, geometry=geometry)
                t0 = time.process_time()
                d = diagnose(data, spaces, Settings(noise_um=1e3 * NOISE_MM, seed=seed),
                             geometry=g, on_demand=solver)
                row[f"{mode}_diagnose_cpu_s"] = time.process_time() - t0
                row[f"{mode}_verdict"] = f"{d['verdict']}:{d['cause']}"
    return row


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--space-dir", default=None)
    ap.add_argument("--subjects", type=int, default=6)
    ap.add_argument("--diagnose", type=int, default=2)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default="benchmarks/out/geometry_subject_cost.csv")
    args = ap.parse_args(argv)

    from skinsuction.space import resolve_space

    space_dir = str(resolve_space(args.space_dir).path)
    rng = np.random.default_rng(args.seed)
    jobs = []
    for i in range(args.subjects):
        probes = (2.0, 6.0) if i % 2 == 0 else (4.0, 8.0)
        draw = (probes, round(float(rng.uniform(0.5, 2.5)), 2),
                round(float(10 ** rng.uniform(math.log10(0.5), 1.0)), 2),
                float(10 ** rng.uniform(-2, math.log10(0.06))),
                float(10 ** rng.uniform(math.log10(0.003), math.log10(0.3))))
        jobs.append((i, args.seed + 2000 + i, draw, space_dir, i < args.diagnose))
    df, seconds = run_rows(_run, jobs, args.workers, args.out)
    out = Path(args.out)
    ok = df[df["error"].isna()] if "error" in df else df
    print(f"{len(df)} subjects ({args.seed=}), {len(ok)} with both FE curves to 100 mbar; "
          f"{seconds:.0f} s wall on {args.workers} workers")
    for mode in ("read", "solved"):
        c = ok[f"{mode}_identify_cpu_s"]
        print(f"identify, rays {mode:6s}: CPU median {c.median():.1f} s, max {c.max():.1f} s; "
              f"ray sets solved per subject: median {ok[f'{mode}_ray_sets_solved'].median():.0f}")
    for k in ("X1d", "X1h"):
        width = np.log(ok[f"solved_{k}_hi"] / ok[f"solved_{k}_lo"])
        shift = np.abs(np.log(ok[f"read_{k}"] / ok[f"solved_{k}"])) / width
        print(f"{k}: |estimate read - solved| / interval width (log): median "
              f"{shift.median():.3f}, max {shift.max():.3f}; within a tenth in "
              f"{int((shift <= 0.1).sum())}/{len(ok)}")
    if "read_diagnose_cpu_s" in ok:
        d = ok[ok["read_diagnose_cpu_s"].notna()]
        for mode in ("read", "solved"):
            print(f"diagnose, rays {mode:6s}: CPU " + ", ".join(
                f"{v:.0f} s" for v in d[f"{mode}_diagnose_cpu_s"]))
        print("verdicts equal in "
              f"{int((d['read_verdict'] == d['solved_verdict']).sum())}/{len(d)}: "
              + "; ".join(f"{a} | {b}" for a, b in zip(d["read_verdict"], d["solved_verdict"])))
    print(f"written: {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
