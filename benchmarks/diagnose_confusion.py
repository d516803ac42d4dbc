"""Confusion matrix of `skinsuction diagnose` over the physiological domain.

For each true cause (none and every cause of the scale-free space)
``--per-cause`` virtual experiments are drawn from seeds across the
physiological domain (skinsuction.evaluation.WIDE_DOMAIN: X1d
log-uniform 0.005-0.15 MPa, X1h/X1d 0.003-0.1, noise 1-5 µm, protocols to 100
or 300 mbar, X2d/X1d up to 500, t_d 0.5-2.5 mm, lambda0 up to 1.25), made by
direct FE runs on the space's mesh (both probes), written as measured CSV
files and diagnosed with the default settings.  Each draw is also judged
detectable or not, independently of the diagnosis (the neo-Hookean model's best
fit to the noise-free true curves leaves a misfit that would earn an extra
parameter and forms a pattern), and, for a cause, distinguishable or not (every
cause's model fitted to the same noise-free curves: the best other cause stays at
least the tie rule's BIC gap behind the true one).  Prints the confusion matrix over
all draws and over the detectable ones, the detectable fraction, the rate of the
right cause (over the detectable and over the distinguishable draws, and right or tied),
the false-alarm rate, the median errors and the time of one diagnosis; writes
every draw to --out and the detectability map next to it.  Asserts nothing.

    python benchmarks/diagnose_confusion.py [--space-dir results/simulated_space/scale_free] \\
        [--per-cause 40] [--workers 2] [--out benchmarks/out/diagnose_confusion.csv]

It takes tens of minutes (2 FE runs and one diagnosis per draw).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import pandas as pd  # noqa: E402

_SPACES = None


def _spaces(space_dir):
    global _SPACES
    if _SPACES is None:
        from skinsuction.space import read_ray_spaces

        _SPACES = read_ray_spaces(space_dir)
    return _SPACES


_SOLVER = None


def one_draw(job):
    global _SOLVER
    from skinsuction.diagnose import Settings
    from skinsuction.evaluation import run_draw
    from skinsuction.space import OnDemandRays

    truth, seed, space_dir, settings, cache, domain, ray_cache, solver = job
    spaces = _spaces(space_dir)
    if _SOLVER is None:
        _SOLVER = OnDemandRays(spaces["neo_hookean"].spec, cache_dir=ray_cache)
    return run_draw(truth, seed, spaces, Settings(**settings), cache_dir=cache, domain=domain,
                    on_demand=_SOLVER, solver=solver)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--space-dir", default="results/simulated_space/scale_free")
    ap.add_argument("--per-cause", type=int, default=40)
    ap.add_argument("--seed", type=int, default=1000, help="first seed (default 1000)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default="benchmarks/out/diagnose_confusion.csv")
    ap.add_argument("--repeats", type=int, default=None,
                    help="window focusing runs per fit (default: the package default)")
    ap.add_argument("--no-space-error", action="store_true",
                    help="leave the space's correlated error out of the diagnosis "
                         "(Settings.space_error=False), for comparison")
    ap.add_argument("--no-discretisation-error", action="store_true",
                    help="leave the space's discretisation error out of the correlated term "
                         "(skinsuction.identify.measured_fit.DISCRETISATION_ERROR_RMS), for "
                         "comparison")
    ap.add_argument("--pattern-gate", action=argparse.BooleanOptionalAction, default=None,
                    help="name a cause only once the smooth-pattern test fires first "
                         "(Settings.pattern_gate; default: the package's, off); either way "
                         "both rules' verdicts are in each row and both summaries printed")
    ap.add_argument("--truths", nargs="+", default=None,
                    help="true causes to draw (default: none and every cause of the space)")
    ap.add_argument("--cache", default="benchmarks/out/diagnose_confusion_fe",
                    help="folder of the draws' noise-free FE curves, reused when the "
                         "diagnosis changes ('' to solve every draw again)")
    ap.add_argument("--given-dermis-sd", type=float, default=None, metavar="MM",
                    help="draw the dermis thickness (uniform 0.5-2.5 mm) and give it in each "
                         "file's header with a Gaussian error of this sd (e.g. 0.1): the "
                         "diagnosis then uses it, and dermis_thickness is no cause; the "
                         "neo-Hookean rays of each draw are solved on demand")
    ap.add_argument("--given-hypodermis-sd", type=float, default=None, metavar="MM",
                    help="also draw the hypodermis thickness (log-uniform 0.5-10 mm) and give "
                         "it in the header with a Gaussian error of this sd (e.g. 0.2): "
                         "hypodermis_thickness is then no cause either")
    ap.add_argument("--probe-pairs", default="2+6,4+8",
                    help="probe pairs drawn evenly (default 2+6,4+8)")
    ap.add_argument("--ray-cache", default="benchmarks/out/on_demand",
                    help="folder of the rays solved on demand")
    ap.add_argument("--solver", default="space",
                    help="discretisation or FE code of the virtual experiments: space (the "
                         "space's own, default), refined, quad9, felupe or calculix "
                         "(skinsuction.evaluation.OTHER_SOLVERS; CalculiX refuses "
                         "pre-tension draws)")
    args = ap.parse_args(argv)

    from skinsuction.evaluation import UNDIAGNOSED, given_keywords, summarise, under_rule
    from skinsuction.figures.detectability import plot_detectability

    if args.no_discretisation_error:
        # read at every call, and inherited by the forked workers
        from skinsuction.identify import _space_error

        _space_error.DISCRETISATION_ERROR = False
    spaces = _spaces(args.space_dir)
    domain = {"probe_pairs": tuple(tuple(float(q) for q in pair.split("+"))
                                   for pair in args.probe_pairs.split(","))}
    causes = [n for n in spaces if n != "neo_hookean"]
    if args.given_dermis_sd is not None:
        domain["given_dermis_thickness"] = {"range": (0.5, 2.5), "sd": args.given_dermis_sd}
    if args.given_hypodermis_sd is not None:
        domain["given_hypodermis_thickness"] = {"range": (0.5, 10.0),
                                                "sd": args.given_hypodermis_sd}
    causes = [n for n in causes if spaces[n].cause.keyword not in given_keywords(domain)]
    settings = {} if args.repeats is None else {"repeats": args.repeats}
    if args.no_space_error:
        settings["space_error"] = False
    if args.pattern_gate is not None:
        settings["pattern_gate"] = args.pattern_gate
    cache = args.cache or None
    jobs = [(truth, args.seed + 100000 * k + i, args.space_dir, settings, cache, domain,
             args.ray_cache, args.solver)
            for k, truth in enumerate(["none", *causes]) for i in range(args.per_cause)
            if args.truths is None or truth in args.truths]
    print(f"{len(jobs)} virtual experiments ({args.per_cause} per true cause), space "
          f"{args.space_dir}, solver {args.solver}, {args.workers} worker(s)", flush=True)
    t0 = time.perf_counter()
    rows = []
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    partial = out.with_suffix(".partial.csv")
    # every draw is kept as it ends: a run given the dermis takes hours, and one cut
    # off must not lose the draws it finished
    every = 1 if given_keywords(domain) else 10

    def done(i, row):
        rows.append(row)
        if i % every == 0:
            pd.DataFrame(rows).to_csv(partial, index=False)
            print(f"  {i}/{len(jobs)} ({time.perf_counter() - t0:.0f} s): {row.get('truth')} "
                  f"named {row.get('named')}", flush=True)

    if args.workers > 1:
        from concurrent.futures import ProcessPoolExecutor

        with ProcessPoolExecutor(args.workers) as pool:
            for i, row in enumerate(pool.map(one_draw, jobs), 1):
                done(i, row)
    else:
        for i, job in enumerate(jobs, 1):
            done(i, one_draw(job))
    df = pd.DataFrame(rows)
    for col in ("cpu_seconds", "wall_seconds", "verdict", "detectable"):
        if col not in df:
            df[col] = float("nan")
    df.to_csv(out, index=False)
    partial.unlink(missing_ok=True)
    plot_detectability(df, out.with_suffix(".png"))

    s = summarise(df, causes)
    pd.set_option("display.width", 160)
    print("\nConfusion matrix over the detectable draws (rows: true cause, columns: named)")
    print(s["detectable"].to_string())
    print("\nConfusion matrix over all draws (detectable or not)")
    print(s["all"].to_string())
    print("\nPer true cause (fractions; errors are medians of |relative error|, lambda0 as "
          "lambda0 - 1):")
    print(s["rates"].to_string(index=False, float_format=lambda x: f"{x:.3g}"))
    from skinsuction.diagnose import Settings

    gate = Settings(**settings).pattern_gate
    if f"named_{'ungated' if gate else 'gated'}" in df:
        other = summarise(under_rule(df, not gate), causes)
        print(f"\nThe same fits under the rule {'without' if gate else 'with'} the pattern "
              "gate: over its detectable draws")
        print(other["detectable"].to_string())
        print(other["rates"].to_string(index=False, float_format=lambda x: f"{x:.3g}"))
    from skinsuction.evaluation import interval_coverage

    print("\nCoverage of the 95 % intervals of the model named, over the draws named right:")
    print(interval_coverage(df).to_string(index=False, float_format=lambda x: f"{x:.3g}"))
    pt = df[(df["truth"] == "pre_tension") & ~df["named"].isin(UNDIAGNOSED)]
    if len(pt):
        print(f"\nInitial in-plane stress of the pre-tension draws: "
              f"{pt['initial_stress_kpa'].min():.2g}-{pt['initial_stress_kpa'].max():.2g} kPa "
              f"(median {pt['initial_stress_kpa'].median():.2g})")
    for _, r in df[df["named"] == "input_rejected"].iterrows():
        print(f"  input rejected: {r['truth']} seed {r['seed']}: {r['error']}")
    for _, r in df[df["named"] == "solver_refused"].iterrows():
        print(f"  solver refused: {r['truth']} seed {r['seed']}: {r['error']}")
    ok = df[~df["named"].isin(UNDIAGNOSED)]
    solved = df[~df["fe_cached"].fillna(True).astype(bool)]
    print(f"\nOne diagnosis: median {ok['cpu_seconds'].median():.2f} s CPU "
          f"({ok['wall_seconds'].median():.2f} s wall), max {ok['cpu_seconds'].max():.2f} s CPU; "
          f"FE of one virtual experiment: median {solved['fe_seconds'].median():.1f} s "
          f"({len(solved)} solved, {len(df) - len(solved)} from the cache); "
          f"FE failures {int((df['named'] == 'fe_failed').sum())}, inputs rejected "
          f"{int((df['named'] == 'input_rejected').sum())}")
    print(f"total {time.perf_counter() - t0:.0f} s; rows written to {out}, map to "
          f"{out.with_suffix('.png')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
