"""Coverage of the 95 % profile-likelihood intervals, measured on FE virtual experiments.

Draws N seeded virtual experiments across the physiological domain (X1d
log-uniform 0.005-0.15 MPa, X1h/X1d log-uniform 0.003-0.1, noise sd uniform
1-5 µm, pressures 0, 2, ..., 100 mbar), each a direct FE run of both probes on
the mesh of the scale-free space (fallbacks spliced as for its rays) plus
Gaussian noise.  Each is identified on the scale-free space with intervals,
for three probe sets: the 6 mm curve alone, the 2 mm curve alone, and both
(weighted objective).  Prints, per probe set and parameter, the empirical
coverage of the nominal 95 % intervals (with its binomial 95 % range), the
median relative width, and the share of intervals open at an edge of the space.

The noise-free FE curves are cached (``--cache``), so a change of the interval
method is re-measured in seconds; the noise is drawn from the seed at every run.

    python benchmarks/interval_coverage.py [--draws 200] [--space DIR] [--cache FILE]
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np

RANGES = {"x1d_mpa": (0.005, 0.15), "x1h_over_x1d": (0.003, 0.1), "noise_um": (1.0, 5.0)}
PRESSURES = np.arange(0.0, 101.0, 2.0)
PROBE_SETS = {"6 mm": {"objective": "single", "probe_mm": 6.0},
              "2 mm": {"objective": "single", "probe_mm": 2.0},
              "both": {"objective": "weighted"}}


def draw(seed):
    rng = np.random.default_rng(np.random.SeedSequence(seed).spawn(1)[0])
    x1d = math.exp(rng.uniform(*np.log(RANGES["x1d_mpa"])))
    ratio = math.exp(rng.uniform(*np.log(RANGES["x1h_over_x1d"])))
    return x1d, x1d * ratio, rng.uniform(*RANGES["noise_um"])


def clean_curves(seeds, cache: Path, mesh, fallback, probes=(2.0, 6.0)):
    """{seed: {probe: FE curve}} from the cache, computing the missing draws and probes."""
    from skinsuction.space import solve_with_fallbacks

    have = json.loads(cache.read_text()) if cache.exists() else {}
    todo = [s for s in seeds
            if any(f"{p:g}" not in have.get(str(s), {}) for p in probes)]
    t0 = time.perf_counter()
    for i, s in enumerate(todo):
        x1d, x1h, _ = draw(s)
        curves = dict(have.get(str(s), {}))
        for probe in (p for p in probes if f"{p:g}" not in curves):
            c, _, _ = solve_with_fallbacks(dict(x1d=x1d, x1h=x1h, probe_mm=probe,
                                                bottom="fixed"), PRESSURES, mesh, fallback,
                                           label=f"draw {s}", splice=True)
            curves[f"{probe:g}"] = [None if not np.isfinite(v) else float(v)
                                    for v in c.deflection_mm]
        have[str(s)] = curves
        if (i + 1) % 10 == 0 or i + 1 == len(todo):
            cache.parent.mkdir(parents=True, exist_ok=True)
            tmp = cache.with_suffix(".tmp")
            tmp.write_text(json.dumps(have))
            tmp.replace(cache)
            print(f"  FE draws {i + 1}/{len(todo)} ({time.perf_counter() - t0:.0f} s)",
                  flush=True)
    return {s: {float(k): np.array(v, dtype=float) for k, v in have[str(s)].items()}
            for s in seeds}


def main(argv=None):
    from skinsuction.identify.measured_fit import identify_data, load_space
    from skinsuction.measured import MeasuredCurve, MeasuredData

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--draws", type=int, default=200)
    ap.add_argument("--first-seed", type=int, default=5000)
    ap.add_argument("--space", default="results/simulated_space/scale_free")
    ap.add_argument("--cache", default="results/benchmarks/interval_coverage_fe.json")
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--curves", choices=("fe", "space"), default="fe",
                    help="fe: direct FE runs (the benchmark); space: the interpolated space's "
                         "own curves at the truth (separates the interval method from the "
                         "error of the space)")
    ap.add_argument("--uncorrelated", action="store_true",
                    help="leave out the correlated space-error term of the likelihood "
                         "(SPACE_ERROR_RMS), for comparison")
    args = ap.parse_args(argv)
    if args.uncorrelated:
        from skinsuction.identify import measured_fit

        measured_fit.SPACE_ERROR_CORRELATED = False

    space = load_space(args.space)
    spec = space.probe(6.0).space.spec
    mesh, fallback = dict(spec.mesh or {}), spec.fallback
    seeds = list(range(args.first_seed, args.first_seed + args.draws))
    clean = clean_curves(seeds, Path(args.cache), mesh, fallback)

    rows, skipped, failures = [], 0, []
    t0 = time.process_time()
    for s in seeds:
        x1d, x1h, noise = draw(s)
        if any(not np.all(np.isfinite(c)) for c in clean[s].values()):
            skipped += 1  # the FE run stopped: no honest curve to identify
            continue
        rng = np.random.default_rng([s, 1])
        curves = []
        for probe in (6.0, 2.0):
            base = clean[s][probe]
            if args.curves == "space":
                sl = space.probe(probe)
                base = sl.interpolant_at(PRESSURES)(sl.from_moduli([[x1d, x1h]]))[0]
            m = base + rng.normal(0.0, 1e-3 * noise, PRESSURES.size)
            m[PRESSURES == 0] = 0.0
            curves.append(MeasuredCurve(probe, PRESSURES, m))
        data = MeasuredData(f"draw {s}", tuple(curves))
        for name, kw in PROBE_SETS.items():
            try:
                r = identify_data(data, space, repeats=args.repeats, seed=s, **kw)
            except ValueError as err:  # e.g. beyond the reach of the space
                failures.append((s, name, str(err)[:160]))
                continue
            iv = r["intervals"]
            if not iv:
                failures.append((s, name, "; ".join(r["warnings"])[:160]))
                continue
            for par, truth in (("X1d", x1d), ("X1h", x1h)):
                i = iv[par]
                rows.append({"set": name, "parameter": par, "seed": s,
                             "covered": i["lower"] <= truth <= i["upper"],
                             "rel_width": (i["upper"] - i["lower"]) / truth,
                             "open": i["lower_open"] or i["upper_open"],
                             "scaled": iv["misfit_scale"] > 1})
    cpu = time.process_time() - t0
    import pandas as pd

    df = pd.DataFrame(rows)
    n = df.groupby(["set", "parameter"]).size()
    print(f"\n{len(seeds) - skipped} draws ({skipped} skipped: FE run stopped), "
          f"{cpu / max(1, len(df) // 2):.3f} s CPU per identification with intervals, "
          f"{len(failures)} identifications without intervals\n")
    for f in failures:
        print("  no interval:", *f)
    print("| probe set | parameter | coverage | binomial 95 % range at 95 % | "
          "median relative width | open at an edge | misfit-scaled |")
    print("|---|---|---|---|---|---|---|")
    for (name, par), g in df.groupby(["set", "parameter"], sort=False):
        k = len(g)
        half = 1.96 * math.sqrt(0.95 * 0.05 / k)
        print(f"| {name} | {par} | {100 * g['covered'].mean():.1f} % | "
              f"{100 * (0.95 - half):.1f}-{100 * (0.95 + half):.1f} % | "
              f"{100 * g['rel_width'].median():.3g} % | {100 * g['open'].mean():.0f} % | "
              f"{100 * g['scaled'].mean():.0f} % |")
    return df, n


if __name__ == "__main__":
    main()
