"""Identification of time curves on FE virtual experiments (issue 25, part 4).

N skins (seeded): X1d log-uniform in [--x1d-min, --x1d-max] MPa (default 0.06-0.15:
400 mbar is reached by the FE on the default mesh), X1h/X1d log-uniform 0.01-0.3, one
Prony term for both layers, g log-uniform 0.1-1, tau log-uniform in 5-20 ms (even
draws) or 0.1-1 s (odd draws), the literature's two time constants.  Each: mode 1,
400 mbar, 3 s on / 2 s off, 2 cycles, 10 ms switches on the 100 Hz clock, FE time
solves (``simulate_history``, default mesh: the space's) under the 6 mm and 2 mm
probes, noise 3 µm, rounded to 0.01 mm.  Fitted (one term) by
``skinsuction.identify.time_curves`` on the shipped space, with both probes and with
6 mm alone, with the model-error likelihood ("all") and suction-on points only
("on").  Prints median and 90th percentile |relative errors|, the coverage of the
95 % intervals and their median width (relative to the estimate); writes ``benchmarks/out/time_identify.csv``.  The FE curves are kept
in ``benchmarks/out/time_identify_fe/`` (one CSV per draw, named by the seed, the X1d
range and the draw) and read from there on a rerun (``--no-cache`` solves them again):
a change of the fit or of the intervals is measured on the same virtual experiments.

    python benchmarks/time_identify.py [--draws 16] [--seed 0] [--no-cache] [--fe-correction 2]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import pandas as pd

from skinsuction.evaluation import mode1_suction, virtual_curve, write_time_csv
from skinsuction.identify.time_curves import identify_time_data
from skinsuction.measured import load_time_curves
from skinsuction.space import load_space
from skinsuction.viscoelastic import Prony

PARAMS = ("X1d", "X1h", "g_1", "tau_1")


def draw(rng, i, x1d_range):
    lx = np.log10(x1d_range)
    x1d = 10 ** rng.uniform(*lx)
    ratio = 10 ** rng.uniform(-2, np.log10(0.3))
    g = 10 ** rng.uniform(-1, 0)
    tau = 10 ** (rng.uniform(np.log10(5e-3), np.log10(2e-2)) if i % 2 == 0
                 else rng.uniform(-1, 0))
    return x1d, ratio, g, tau


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--draws", type=int, default=16)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--x1d-min", type=float, default=0.06)
    ap.add_argument("--x1d-max", type=float, default=0.15)
    ap.add_argument("--fe-correction", type=int, default=2,
                    help="steps of the FE correction of each fit (0: the fast path alone)")
    ap.add_argument("--no-cache", action="store_true",
                    help="solve the FE curves again (not read from benchmarks/out)")
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    space = load_space()
    rows = []
    cache = Path(__file__).parent / "out" / "time_identify_fe"
    cache.mkdir(parents=True, exist_ok=True)
    for i in range(args.draws):
        x1d, ratio, g, tau = draw(rng, i, (args.x1d_min, args.x1d_max))
        truth = {"X1d": x1d, "X1h": x1d * ratio, "g_1": g, "tau_1": tau}
        t0 = time.perf_counter()
        path = cache / f"seed{args.seed}_x1d{args.x1d_min:g}-{args.x1d_max:g}_draw{i}.csv"
        if args.no_cache or not path.exists():
            curves = []
            try:
                for k, probe in enumerate((6.0, 2.0)):
                    t, p, d, _, _ = virtual_curve(x1d, x1d * ratio, Prony([g], [tau]),
                                                  mode1_suction(), probe_mm=probe,
                                                  seed=args.seed * 1000 + 2 * i + k)
                    curves.append((probe, t, p, d))
            except RuntimeError as err:
                print(f"draw {i}: X1d {x1d:.3g} r {ratio:.3g}: FE failed ({err})")
                rows.append({"draw": i, **truth, "fe_failed": True})
                continue
            write_time_csv(path, curves, [f"truth: X1d {x1d!r} X1h/X1d {ratio!r} g {g!r} "
                                          f"tau {tau!r}"])
        fe_s = time.perf_counter() - t0
        data = load_time_curves(path)
        for probes in ("both", "6"):
            for phases in ("all", "on"):
                t1 = time.perf_counter()
                r = identify_time_data(data, space, terms=1, seed=i, repeats=2, phases=phases,
                                       probes=None if probes == "both" else [6.0],
                                       fe_correction=args.fe_correction)
                fit_s = time.perf_counter() - t1
                iv = r["intervals"]
                row = {"draw": i, "probes": probes, "phases": phases, "fe_s": fe_s,
                       "fit_s": fit_s, "fe_failed": False,
                       "chi2_per_point": r["fit_quality"]["chi2"] / r["fit_quality"]["points"]}
                for k in PARAMS:
                    est = iv[k]["estimate"]
                    row[f"true_{k}"] = truth[k]
                    row[f"est_{k}"] = est
                    row[f"err_{k}"] = est / truth[k] - 1
                    row[f"cover_{k}"] = bool(iv[k]["lower"] <= truth[k] <= iv[k]["upper"])
                    row[f"width_{k}"] = (iv[k]["upper"] - iv[k]["lower"]) / est
                rows.append(row)
                print(f"draw {i} ({probes}, {phases}): X1d {x1d:.3g} r {ratio:.3g} g {g:.3g} "
                      f"tau {tau:.3g} s -> errors "
                      + ", ".join(f"{k} {100 * row[f'err_{k}']:+.1f} %" for k in PARAMS)
                      + f" (FE {fe_s:.0f} s, fit {fit_s:.1f} s)", flush=True)
    table = pd.DataFrame(rows)
    out = Path(__file__).parent / "out"
    out.mkdir(exist_ok=True)
    table.to_csv(out / "time_identify.csv", index=False)
    ok = table[~table["fe_failed"]]
    print(f"\n{ok['draw'].nunique()} draws (of {args.draws}); |relative error| median / "
          "90th percentile, coverage of the 95 % intervals")
    print("| probes | likelihood | tau group | " + " | ".join(PARAMS) + " | coverage "
          + " / ".join(PARAMS) + " | median width / estimate " + " / ".join(PARAMS) + " |")
    for (probes, phases), grp in ok.groupby(["probes", "phases"], sort=False):
        for name, sub in (("all", grp), ("5-20 ms", grp[grp["draw"] % 2 == 0]),
                          ("0.1-1 s", grp[grp["draw"] % 2 == 1])):
            errs = " | ".join(
                f"{100 * np.median(np.abs(sub[f'err_{k}'])):.2g} / "
                f"{100 * np.percentile(np.abs(sub[f'err_{k}']), 90):.2g} %" for k in PARAMS)
            cov = " / ".join(f"{100 * sub[f'cover_{k}'].mean():.0f} %" for k in PARAMS)
            width = " / ".join(f"{100 * np.median(sub[f'width_{k}']):.2g} %" for k in PARAMS)
            print(f"| {probes} | {phases} | {name} | {errs} | {cov} | {width} |")
    print(f"\nmedian time: FE {ok['fe_s'].median():.1f} s per draw (2 probes), fit "
          f"{ok['fit_s'].median():.1f} s")


if __name__ == "__main__":
    main()
