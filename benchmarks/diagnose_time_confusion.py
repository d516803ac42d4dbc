"""The diagnosis of time curves on FE virtual experiments: creep named, elastic not.

Draws (seeded), per class:

* ``viscoelastic_creep``: X1d log-uniform in [--x1d-min, --x1d-max] MPa (default
  0.06-0.15: 400 mbar is reached by the FE time solve on the default mesh), X1h/X1d
  log-uniform 0.01-0.3, one Prony term for both layers, g log-uniform 0.1-1, tau
  log-uniform in 5-20 ms (even draws) or 0.1-1 s (odd draws), the literature's two
  time constants;
* ``none``: the same skins with g = 1e-4 (an elastic skin: its creep, 1e-4 of the
  deflection, is far below the 0.01 mm steps).

Each: mode 1, 400 mbar, 3 s on / 2 s off, 2 cycles, sampled at 100 Hz, FE time solves
(``simulate_history``, independent of the fast path the diagnosis fits) under the 6 and
2 mm probes, noise 3 µm, rounded to 0.01 mm.  A draw is *detectable* when, on the
noise-free curves judged with the noisy file's noise sd, the viscoelastic model earns
its two parameters by the BIC and the elastic misfit, added to the chi^2 that noise
alone gives, passes the misfit test: what the diagnosis needs, in expectation.  Prints the
confusion matrix over the detectable draws, the false-alarm rate over the elastic ones,
and the median and 90th percentile |relative errors| of X1d, g_1, tau_1 of the creep
draws named right; writes ``benchmarks/out/diagnose_time_confusion.csv``.

    python benchmarks/diagnose_time_confusion.py [--per-class 12] [--seed 0]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats

from skinsuction.diagnose import Settings
from skinsuction.diagnose._time import VISCOELASTIC_CREEP, diagnose_time_data
from skinsuction.evaluation import mode1_suction, virtual_curve, write_time_csv
from skinsuction.measured import load_time_curves
from skinsuction.space import load_space
from skinsuction.viscoelastic import Prony

PROBES = (6.0, 2.0)


def draw(rng, i, x1d_range):
    x1d = 10 ** rng.uniform(*np.log10(x1d_range))
    ratio = 10 ** rng.uniform(-2, np.log10(0.3))
    g = 10 ** rng.uniform(-1, 0)
    tau = 10 ** (rng.uniform(np.log10(5e-3), np.log10(2e-2)) if i % 2 == 0
                 else rng.uniform(-1, 0))
    return x1d, ratio, g, tau


def one(space, truth, x1d, ratio, g, tau, seed, tmp):
    suction = mode1_suction(400.0, on_s=3.0, off_s=2.0, cycles=2)
    noisy, exact = [], []
    t0 = time.process_time()
    for k, probe in enumerate(PROBES):
        t, p, d, clean, _ = virtual_curve(x1d, x1d * ratio, Prony([g], [tau]), suction,
                                          probe_mm=probe, seed=seed * 10 + k)
        noisy.append((probe, t, p, d))
        exact.append((probe, t, p, clean))
    fe_s = time.process_time() - t0
    data = load_time_curves(write_time_csv(tmp / f"d{seed}.csv", noisy, ["synthetic: FE"]))
    t0 = time.process_time()
    r = diagnose_time_data(data, space, Settings(seed=seed))
    dg_s = time.process_time() - t0
    sd_um = 1e3 * float(np.mean([c.noise_sd_mm for c in data.curves]))
    clean = load_time_curves(write_time_csv(tmp / f"c{seed}.csv", exact, ["synthetic: FE"]))
    rc = diagnose_time_data(clean, space, Settings(seed=seed, noise_um=sd_um))
    p = r["viscoelastic"]["parameters"]
    # detectable: on the noise-free curves creep earns its parameters (BIC), and the
    # elastic misfit they leave, added to the chi^2 that noise alone gives (its dof),
    # passes the misfit test's 1 - alpha quantile
    el = rc["elastic"]
    dof = el["points"] - el["n_params"]
    misfit = dof + el["chi2"] >= stats.chi2.ppf(1 - Settings().alpha, dof)
    detectable = bool(rc["gain"]["delta_bic"] <= Settings().delta_bic and misfit)
    return {"truth": truth, "seed": seed, "x1d": x1d, "ratio": ratio, "g": g, "tau_s": tau,
            "named": r["named"], "detectable": detectable,
            "clean_elastic_chi2": el["chi2"], "points": el["points"],
            "clean_delta_bic": rc["gain"]["delta_bic"], "delta_bic": r["gain"]["delta_bic"],
            "elastic_misfit_p": r["elastic"]["misfit_p"], "noise_um": sd_um,
            "fit_x1d": p["X1d"], "fit_x1h": p["X1h"], "fit_g": p["g"][0],
            "fit_tau_s": p["tau_s"][0], "elastic_x1d": r["elastic"]["parameters"]["X1d"],
            "fe_cpu_s": fe_s, "diagnosis_cpu_s": dg_s}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--per-class", type=int, default=12)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--x1d-min", type=float, default=0.06)
    ap.add_argument("--x1d-max", type=float, default=0.15)
    ap.add_argument("--classes", nargs="+", default=[VISCOELASTIC_CREEP, "none"],
                    help="true classes drawn (e.g. none alone, for the false-alarm rate)")
    ap.add_argument("--out", default="benchmarks/out/diagnose_time_confusion.csv")
    args = ap.parse_args()
    space = load_space()
    tmp = Path(tempfile.mkdtemp())
    rng = np.random.default_rng(args.seed)
    rows, start = [], time.perf_counter()
    for i in range(args.per_class):
        x1d, ratio, g, tau = draw(rng, i, (args.x1d_min, args.x1d_max))
        for truth, gg in ((VISCOELASTIC_CREEP, g), ("none", 1e-4)):
            if truth not in args.classes:
                continue
            seed = args.seed * 1000 + 2 * i + (truth == "none")
            try:
                rows.append(one(space, truth, x1d, ratio, gg, tau, seed, tmp))
            except Exception as err:  # noqa: BLE001 - a failed draw is recorded, not dropped
                rows.append({"truth": truth, "seed": seed, "x1d": x1d, "ratio": ratio,
                             "g": gg, "tau_s": tau, "named": None,
                             "error": f"{type(err).__name__}: {err}"})
            print(f"  {len(rows)}/{len(args.classes) * args.per_class}: {rows[-1].get('named')} "
                  f"({time.perf_counter() - start:.0f} s)", flush=True)
    df = pd.DataFrame(rows)
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    df.to_csv(args.out, index=False)

    ok = df[df["named"].notna()]
    failed = len(df) - len(ok)
    det = ok[(ok["truth"] == "none") | ok["detectable"].astype(bool)]
    print(f"\n{len(df)} draws ({failed} failed: FE or fit), {args.per_class} per class, "
          f"seed {args.seed}")
    print("\nConfusion over the detectable draws (rows: truth, columns: named)")
    print(pd.crosstab(det["truth"], det["named"]).to_string())
    ve = ok[ok["truth"] == VISCOELASTIC_CREEP]
    vdet = ve[ve["detectable"].astype(bool)]
    right = vdet[vdet["named"] == VISCOELASTIC_CREEP]
    none = ok[ok["truth"] == "none"]
    print(f"\ncreep named right: {len(right)}/{len(vdet)} detectable "
          f"({len(vdet)}/{len(ve)} detectable)")
    print(f"false alarms: {int((none['named'] != 'none').sum())}/{len(none)} elastic draws")
    for name, fit, true in (("X1d", "fit_x1d", "x1d"), ("g_1", "fit_g", "g"),
                            ("tau_1", "fit_tau_s", "tau_s")):
        e = (right[fit] / right[true] - 1).abs()
        for label, sel in (("all", e.index), ("tau 5-20 ms", right.index[right["tau_s"] < 0.05]),
                           ("tau 0.1-1 s", right.index[right["tau_s"] >= 0.05])):
            if len(sel):
                print(f"  {name:6s} {label:12s} |error| median {100 * e[sel].median():.2f} %, "
                      f"90th {100 * e[sel].quantile(0.9):.2f} % (n = {len(sel)})")
    e = (none["elastic_x1d"] / none["x1d"] - 1).abs()
    print(f"  elastic draws: X1d |error| median {100 * e.median():.2f} %")
    print(f"\nCPU per draw: FE {ok['fe_cpu_s'].median():.1f} s, diagnosis "
          f"{ok['diagnosis_cpu_s'].median():.1f} s (medians); total "
          f"{time.perf_counter() - start:.0f} s; rows in {args.out}")


if __name__ == "__main__":
    main()
