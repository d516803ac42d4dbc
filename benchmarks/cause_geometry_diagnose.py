"""Diagnoses of subjects with measured layers: the causes' rays read off their geometry spaces against solved.

    python benchmarks/cause_geometry_diagnose.py [--subjects 8] [--seed 0] [--workers 2]
        [--causes strain_stiffening] [--space-dir DIR] [--read-only]

The check a cause's geometry space must pass before it ships: does a diagnosis
with its rays read (cubic interpolation of log M, solved only where the error
estimate exceeds the tolerance) give the same verdict, the same cause and the
same estimates as the diagnosis with every ray solved by FE at the subject's
layers (the reference, `diagnose --solve-rays`)?

Each subject is an FE virtual experiment (reference mesh, fixed bottom, 0-100 mbar
in 2 mbar steps, 1.5 µm noise) on layers drawn as measured in vivo (t_d uniform
in 0.5-2.5 mm, t_h log-uniform in 0.5-10 mm), the 2 + 6 mm or 4 + 8 mm probes,
X1d log-uniform in 0.01-0.06 MPa, X1h/X1d in 0.003-0.3. Every other subject's
dermis stiffens (X2d/X1d log-uniform in 3-300; the paper's measured fit is about
500). The layers are given, the dermis with an sd of 0.1 mm, so the thickness
causes drop out; the diagnosis weighs the neo-Hookean model against the causes
named by --causes (default: every cause with a geometry space beside the
neo-Hookean one), without the second-effect step (its pair spaces have no
geometry axis yet). Prints CPU per diagnosis, the verdicts side by side, and how
far the estimates differ in units of their 95 % interval width. Asserts nothing.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd
from _pool import run_rows

from geometry_subject_cost import NOISE_MM, P, SD_MM  # same draws' noise and loads


def _data(i, seed, probes, t_d, t_h, x1d, ratio, x2d):
    from skinsuction.measured import MeasuredCurve, MeasuredData
    from skinsuction.model import Skin, simulate

    rng = np.random.default_rng(seed)
    curves = []
    for p in probes:
        c = simulate(Skin.two_layer(x1d, x1d * ratio, x2d=x2d, t_d=t_d, t_h=t_h), probe=p,
                     pressures_mbar=P)
        if not c.converged:
            return None
        m = np.asarray(c.deflection_mm) + rng.normal(0.0, NOISE_MM, P.size)
        m[0] = 0.0
        curves.append(MeasuredCurve(p, P, m))
    return MeasuredData(f"subject {i}", tuple(curves))


def _estimates(report) -> dict:
    """Every parameter of the model the verdict stands on, with its interval."""
    fit = report["extended"] or {"parameters": report["baseline"]["parameters"],
                                 "intervals": report["baseline"]["intervals"]}
    out = {}
    for k, v in fit["parameters"].items():
        iv = (fit["intervals"] or {}).get(k) or {}
        if isinstance(v, (int, float)):
            out[k] = (float(v), iv.get("lower", math.nan), iv.get("upper", math.nan))
    return out


def _run(job):
    from skinsuction.diagnose._diagnose import Settings, diagnose
    from skinsuction.space import Geometry, OnDemandRays, read_ray_spaces

    i, seed, draw, space_dir, causes, modes = job
    probes, t_d, t_h, x1d, ratio, x2d = draw
    data = _data(i, seed, *draw)
    row = {"subject": i, "probes": "+".join(f"{p:g}" for p in probes), "t_d": t_d,
           "t_h": t_h, "x1d": x1d, "x1h": x1d * ratio, "x2d": x2d}
    if data is None:
        return {**row, "error": "FE curve stopped before 100 mbar"}
    g = Geometry(t_d, t_h, given=("t_d", "t_h"), sd={"t_d": SD_MM})
    spaces = {k: v for k, v in read_ray_spaces(space_dir).items()
              if k == "neo_hookean" or k in causes}
    for mode, geometry in modes:
        with tempfile.TemporaryDirectory() as cache:
            solver = OnDemandRays(spaces["neo_hookean"].spec, cache_dir=cache, progress=None,
                                  geometry=geometry)
            t0 = time.process_time()
            d = diagnose(data, spaces, Settings(noise_um=1e3 * NOISE_MM, seed=seed),
                         geometry=g, on_demand=solver, pairs={})
            row[f"{mode}_cpu_s"] = time.process_time() - t0
            row[f"{mode}_ray_sets_solved"] = solver.solved
            row[f"{mode}_verdict"] = f"{d['verdict']}:{d['cause']}"
            row[f"{mode}_ambiguous"] = ",".join(d["ambiguous_with"] or [])
            for k, (v, lo, hi) in _estimates(d).items():
                row[f"{mode}_{k}"], row[f"{mode}_{k}_lo"], row[f"{mode}_{k}_hi"] = v, lo, hi
    return row


def _shift(ok, k) -> pd.Series:
    """|read - solved| in units of the solved interval's width (log scale for moduli)."""
    lo, hi, a, b = (ok[f"solved_{k}_lo"], ok[f"solved_{k}_hi"], ok[f"read_{k}"],
                    ok[f"solved_{k}"])
    positive = (lo > 0) & (a > 0) & (b > 0)
    log_shift = np.abs(np.log(a.where(positive) / b.where(positive))) / np.log(hi / lo)
    return log_shift.where(positive, np.abs(a - b) / (hi - lo))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--space-dir", default=None)
    ap.add_argument("--subjects", type=int, default=8)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--causes", nargs="+", default=None,
                    help="causes weighed (default: those with a geometry space)")
    ap.add_argument("--out", default="benchmarks/out/cause_geometry_diagnose.csv")
    ap.add_argument("--read-only", action="store_true",
                    help="only the diagnosis reading its rays (its cost), no FE reference")
    args = ap.parse_args(argv)
    modes = (("read", "auto"),) if args.read_only else (("read", "auto"), ("solved", None))

    from skinsuction.space import default_geometry_file, resolve_space

    space_dir = str(resolve_space(args.space_dir).path)
    nh_file = default_geometry_file()  # what geometry="auto" reads
    causes = args.causes or sorted(
        f.stem for f in (nh_file.parent.glob("*.parquet") if nh_file else ())
        if f.stem != "neo_hookean")
    print(f"geometry space: {nh_file or 'the shipped one'}; causes weighed: {causes}")
    rng = np.random.default_rng(args.seed)
    jobs = []
    for i in range(args.subjects):
        probes = (2.0, 6.0) if i % 2 == 0 else (4.0, 8.0)
        x1d = float(10 ** rng.uniform(-2, math.log10(0.06)))
        draw = (probes, round(float(rng.uniform(0.5, 2.5)), 2),
                round(float(10 ** rng.uniform(math.log10(0.5), 1.0)), 2), x1d,
                float(10 ** rng.uniform(math.log10(0.003), math.log10(0.3))),
                x1d * float(10 ** rng.uniform(math.log10(3), math.log10(300)))
                if (i // 2) % 2 == 0 else 0.0)
        jobs.append((i, args.seed + 3000 + i, draw, space_dir, causes, modes))
    df, seconds = run_rows(_run, jobs, args.workers, args.out)
    out = Path(args.out)
    ok = df[df["error"].isna()] if "error" in df else df
    print(f"{len(df)} subjects ({args.seed=}), {len(ok)} with both FE curves to 100 mbar; "
          f"{seconds:.0f} s wall on {args.workers} workers")
    for mode, _ in modes:
        c = ok[f"{mode}_cpu_s"]
        print(f"diagnose, rays {mode:6s}: CPU median {c.median():.1f} s, max {c.max():.1f} s; "
              f"ray sets solved: median {ok[f'{mode}_ray_sets_solved'].median():.0f}")
    if args.read_only:
        for _, r in ok.iterrows():
            print(f"  subject {r['subject']} ({r['probes']} mm, t_d {r['t_d']}, t_h {r['t_h']}):"
                  f" {r['read_verdict']}, {r['read_cpu_s']:.1f} CPU-s, "
                  f"{r['read_ray_sets_solved']} ray sets solved")
        print(f"written: {out}")
        return 0
    same = ok["read_verdict"] == ok["solved_verdict"]
    print(f"verdicts equal in {int(same.sum())}/{len(ok)}")
    for _, r in ok.iterrows():
        print(f"  subject {r['subject']} ({r['probes']} mm, t_d {r['t_d']}, t_h {r['t_h']}, "
              f"X2d/X1d {r['x2d'] / r['x1d']:.0f}): read {r['read_verdict']} "
              f"[{r['read_ambiguous']}] | solved {r['solved_verdict']} [{r['solved_ambiguous']}]")
    keys = sorted({c[len("solved_"):-len("_lo")] for c in ok.columns
                   if c.startswith("solved_") and c.endswith("_lo")})
    for k in keys:
        if f"read_{k}" not in ok:
            continue
        both = ok[ok[f"read_{k}"].notna() & ok[f"solved_{k}"].notna()]
        if both.empty:
            continue
        s = _shift(both, k)
        print(f"{k}: |read - solved| / interval width: median {s.median():.3f}, "
              f"max {s.max():.3f}; within a tenth in {int((s <= 0.1).sum())}/{s.notna().sum()}")
    print(f"written: {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
