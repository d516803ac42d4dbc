"""The bias a user avoids by giving the layers: identification on FE virtual experiments.

    python benchmarks/geometry_bias.py [--space-dir DIR] [--draws 20] [--seed 0]
        [--workers 2] [--cache DIR]

Each draw is a virtual experiment made by the FE model (reference mesh, fixed
bottom, neo-Hookean; pressures 0-100 mbar in 2 mbar steps, Gaussian noise of
1.5 µm): the layers drawn as measured in vivo (t_d uniform in 0.5-2.5 mm, t_h
log-uniform in 0.5-10 mm), the probes 2 + 6 mm or 4 + 8 mm, X1d log-uniform in
0.01-0.06 MPa and X1h/X1d log-uniform in 0.003-0.3.  Each is identified twice
(weighted objective, 4 runs polished, 95 % intervals): with the layers given, and
with the paper's assumed 1 + 1 mm; the assumed case is also diagnosed. Prints
the median and 90th percentile of |error| of X1d and X1h, the coverage of the
intervals and the diagnosis's verdicts. Asserts nothing.
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

_CTX = {}
NOISE_MM = 1.5e-3
P = np.arange(0.0, 101.0, 2.0)


def _init(space_dir, cache):
    from skinsuction.space import OnDemandRays, load_space, read_ray_spaces

    spaces = read_ray_spaces(space_dir)
    space = load_space(space_dir, solve_on_demand=False)
    space.on_demand = OnDemandRays(spaces["neo_hookean"].spec, cache_dir=cache)
    _CTX.update(spaces=spaces, space=space)


def _draw(job):
    from skinsuction.diagnose._diagnose import Settings, diagnose
    from skinsuction.identify.measured_fit import identify_data
    from skinsuction.measured import MeasuredCurve, MeasuredData
    from skinsuction.model import Skin, simulate
    from skinsuction.space import Geometry

    i, seed, (probes, t_d, t_h, x1d, ratio) = job
    rng = np.random.default_rng(seed)
    curves = []
    for p in probes:
        c = simulate(Skin.two_layer(x1d, x1d * ratio, t_d=t_d, t_h=t_h), probe=p, pressures_mbar=P)
        if not c.converged:
            return {"draw": i, "error": f"FE stopped at {c.last_converged_mbar:g} mbar"}
        m = np.asarray(c.deflection_mm) + rng.normal(0.0, NOISE_MM, P.size)
        m[0] = 0.0
        curves.append(MeasuredCurve(p, P, m))
    data = MeasuredData(f"draw {i}", tuple(curves))
    row = {"draw": i, "probes": "+".join(f"{p:g}" for p in probes), "t_d": t_d, "t_h": t_h,
           "x1d": x1d, "x1h": x1d * ratio}
    t0 = time.process_time()
    for label, g in (("given", Geometry(t_d, t_h, given=("t_d", "t_h"))),
                     ("assumed", Geometry())):
        r = identify_data(data, _CTX["space"], objective="weighted", repeats=4, seed=seed,
                          noise_um=1e3 * NOISE_MM, geometry=g)
        est, iv = r["estimate"], r["intervals"] or {}
        for k, key in (("X1d", "x1d_mpa"), ("X1h", "x1h_mpa")):
            truth = row[k.lower()]
            row[f"{label}_{k}_error"] = est[key] / truth - 1
            ivk = iv.get(k) or {}
            row[f"{label}_{k}_covered"] = bool(ivk and ivk["lower"] <= truth <= ivk["upper"])
        row[f"{label}_E"] = r["E"]["at_estimate"]
        row[f"{label}_cpu_s"] = time.process_time() - t0
        t0 = time.process_time()
    d = diagnose(data, _CTX["spaces"], Settings(noise_um=1e3 * NOISE_MM, repeats=1,
                                                holdout=False, seed=seed),
                 geometry=Geometry())
    row["assumed_cause"] = d["cause"]
    row["assumed_verdict"] = d["verdict"]
    return row


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--space-dir", default="results/simulated_space/scale_free")
    ap.add_argument("--draws", type=int, default=20)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--cache", default="benchmarks/out/on_demand")
    ap.add_argument("--out", default="benchmarks/out/geometry_bias.csv")
    args = ap.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    jobs = []
    for i in range(args.draws):
        probes = (2.0, 6.0) if i % 2 == 0 else (4.0, 8.0)
        jobs.append((i, args.seed + 1000 + i, (
            probes, round(float(rng.uniform(0.5, 2.5)), 2),
            round(float(10 ** rng.uniform(math.log10(0.5), 1.0)), 2),
            float(10 ** rng.uniform(-2, math.log10(0.06))),
            float(10 ** rng.uniform(math.log10(0.003), math.log10(0.3))))))
    t0 = time.perf_counter()
    with ProcessPoolExecutor(args.workers, initializer=_init,
                             initargs=(args.space_dir, args.cache)) as pool:
        rows = list(pool.map(_draw, jobs))
    df = pd.DataFrame(rows)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    df.to_csv(out, index=False)
    ok = df[df.get("error").isna()] if "error" in df else df
    print(f"{len(df)} draws ({args.seed=}), {len(ok)} with both FE curves to 100 mbar; "
          f"{time.perf_counter() - t0:.0f} s wall on {args.workers} workers")
    for label in ("given", "assumed"):
        for k in ("X1d", "X1h"):
            e = ok[f"{label}_{k}_error"].abs()
            print(f"{label:8s} {k}: |error| median {100 * e.median():.1f} %, 90th percentile "
                  f"{100 * e.quantile(0.9):.1f} %, max {100 * e.max():.1f} %; 95 % interval "
                  f"covers the truth in {int(ok[f'{label}_{k}_covered'].sum())}/{len(ok)}")
    print("diagnosis with the assumed 1 + 1 mm layers: "
          + ", ".join(f"{k} {v}" for k, v in ok["assumed_cause"].value_counts().items()))
    print(f"written: {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
