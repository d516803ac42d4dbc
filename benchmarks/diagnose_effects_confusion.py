"""Single and paired effects in Cutometer time curves: named effect by effect? (prints
figures; asserts nothing).

Classes of skin (seeded draws; X1d log-uniform 0.03-0.12 MPa, X1h/X1d 0.01-0.3):

* ``none``: elastic (g = 1e-4, far below the 0.01 mm steps);
* ``viscoelastic_creep``: one Prony term on both layers, g 0.1-1, tau 0.1-1 s;
* ``strain_stiffening``: X2d/X1d log-uniform 2-30, no creep;
* ``pre_tension``: lambda0 1.03-1.15, no creep;
* ``viscoelastic_creep+strain_stiffening`` and ``viscoelastic_creep+pre_tension``;
* ``hypodermis_creep``: creep (g 0.3-2) in the hypodermis only (the dermis's g 1e-4):
  the effect is creep, and two probes should tell its layer (``creep_layers``).

Designs: mode 1 (400 mbar, 2 s on / 2 s off, 2 cycles, 50 Hz) on the 2 mm probe alone
and on 2 + 8 mm.  FE time solves (``virtual_skin_curve``: independent of the fast path
and of the space the diagnosis reads), noise 3 µm, rounded to 0.01 mm.

An effect of the truth is *detectable* when, on the noise-free curves judged with the
noisy file's sd, the model of the true effects beats the model without it by the
decision's |delta_bic| (with the noise's expected chi^2 added, the model without it
misfits).  Prints, per design: each effect's rate named among the draws where it is
detectable (and right-or-tied), both effects of a pair named where both are
detectable, false effects on the elastic draws, wrong effects that are not tied on any
draw, the median errors of X1d, X2d, g, tau on the draws named right, CPU per
diagnosis; writes ``benchmarks/out/diagnose_effects_confusion.csv``.

    python benchmarks/diagnose_effects_confusion.py [--per-class 8] [--seed 0] [--workers 2]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from multiprocessing import get_context
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from scipy import stats  # noqa: E402

CREEP, STIFF, PRE = "viscoelastic_creep", "strain_stiffening", "pre_tension"
CLASSES = ("none", CREEP, STIFF, PRE, f"{CREEP}+{STIFF}", f"{CREEP}+{PRE}", "hypodermis_creep")
DESIGNS = {"mode 1, 2 mm": (2.0,), "mode 1, 2 + 8 mm": (2.0, 8.0)}


def draw(rng, truth):
    # creep in the hypodermis only: the effect is creep, its layer the hypodermis
    effects = ([] if truth == "none" else [CREEP] if truth == "hypodermis_creep"
               else truth.split("+"))
    s = {"x1d": 10 ** rng.uniform(np.log10(0.03), np.log10(0.12)),
         "ratio": 10 ** rng.uniform(-2, np.log10(0.3)),
         "g": 10 ** rng.uniform(-1, 0) if CREEP in effects else 1e-4,
         "tau_s": 10 ** rng.uniform(-1, 0),
         "x2_over_x1d": 10 ** rng.uniform(np.log10(2), np.log10(30)) if STIFF in effects else 0.0,
         "lambda0": rng.uniform(1.03, 1.15) if PRE in effects else 1.0,
         "creep_layer": "hypodermis" if truth == "hypodermis_creep" else
                        "both" if CREEP in effects else "none"}
    if truth == "hypodermis_creep":
        s["g"] = 10 ** rng.uniform(np.log10(0.3), np.log10(2))
    return effects, s


def _skin(s):
    from skinsuction.model import Skin
    from skinsuction.viscoelastic import Prony

    skin = Skin.two_layer(s["x1d"], s["x1d"] * s["ratio"], x2d=s["x2_over_x1d"] * s["x1d"],
                          prestretch=s["lambda0"], spectrum=Prony([s["g"]], [s["tau_s"]]))
    if s["creep_layer"] == "hypodermis":
        skin = skin.replace({"dermis.spectrum.g[0]": 1e-4})
    return skin


def one(job):
    from skinsuction.diagnose import Settings
    from skinsuction.diagnose._time import diagnose_time_data
    from skinsuction.diagnose._time_effects import EffectFitter
    from skinsuction.evaluation import mode1_suction, virtual_skin_curve, write_time_csv
    from skinsuction.identify.time_curves import prepare_time_fit
    from skinsuction.measured import load_time_curves
    from skinsuction.space import load_space

    design, probes, truth, effects, s, seed, tmp = job
    row = {"design": design, "truth": truth, "seed": seed, **s}
    try:
        space = load_space()
        suction = mode1_suction(400.0, on_s=2.0, off_s=2.0, cycles=2)
        noisy, exact = [], []
        t0 = time.process_time()
        for k, probe in enumerate(probes):
            t, p, d, clean, _ = virtual_skin_curve(_skin(s), suction, probe_mm=probe,
                                                   rate_hz=50.0, seed=seed * 10 + k)
            noisy.append((probe, t, p, d))
            exact.append((probe, t, p, clean))
        row["fe_cpu_s"] = time.process_time() - t0
        data = load_time_curves(write_time_csv(Path(tmp) / f"n{seed}.csv", noisy, ["FE"]))
        settings = Settings(seed=seed)
        t0 = time.process_time()
        r = diagnose_time_data(data, space, settings)
        row["diagnosis_cpu_s"] = time.process_time() - t0
        sd_um = 1e3 * float(np.mean([c.noise_sd_mm for c in data.curves]))
        # detectability on the noise-free curves, judged with the noisy file's sd
        clean = load_time_curves(write_time_csv(Path(tmp) / f"c{seed}.csv", exact, ["FE"]))
        cs = Settings(seed=seed, noise_um=sd_um)
        prep = prepare_time_fit(clean, space, noise_um=sd_um)
        fitter = EffectFitter(prep, cs, [STIFF, PRE])
        full = fitter.fit(tuple(effects))
        for e in effects:
            without = fitter.fit(tuple(x for x in effects if x != e))
            dof = without.n_points - without.n_params
            misfits = dof + without.chi2 >= stats.chi2.ppf(1 - cs.alpha, dof)
            row[f"detectable_{e}"] = bool(full.bic - without.bic <= cs.delta_bic and misfits)
        cl = r.get("creep_layers") or {}
        row.update({"layers_tested": bool(cl.get("tested")), "creeping": cl.get("creeping"),
                    "layers_delta_bic": cl.get("delta_bic")})
        row.update({"named": ",".join(r["effects"]), "verdict": r["verdict"],
                    "ambiguous_with": ",".join(r.get("ambiguous_with") or []),
                    "creep_terms": r["creep_terms"], "noise_um": sd_um})
        fp = r["final"]["parameters"]
        row.update({"fit_x1d": fp["X1d"], "fit_x2d": fp.get("X2d"),
                    "fit_lambda0": fp.get("lambda0"),
                    "fit_g": (fp.get("g") or [None])[-1], "fit_tau_s": (fp.get("tau_s") or [None])[-1]})
    except Exception as err:  # noqa: BLE001 - a failed draw is recorded, not dropped
        row["error"] = f"{type(err).__name__}: {' '.join(str(err).split())[:300]}"
    return row


def summarise(df):
    ok = (df[df["error"].isna()] if "error" in df else df).copy()
    ok["truth"] = ok["truth"].replace({"hypodermis_creep": CREEP})
    for col in ("named", "ambiguous_with"):
        ok[col] = ok[col].fillna("").astype(str)
    print(f"{len(df)} draws, {len(df) - len(ok)} failed (FE or fit)")
    for design, g in ok.groupby("design", sort=False):
        print(f"\n## {design} ({len(g)} draws)\n")
        print("| effect | detectable | named where detectable | right or tied |")
        print("|---|---|---|---|")
        for e in (CREEP, STIFF, PRE):
            col = f"detectable_{e}"
            has = g[g["truth"].str.contains(e)]
            det = has[has[col].fillna(False).astype(bool)] if col in has else has.iloc[:0]
            named = det["named"].str.split(",").apply(lambda x: e in x)
            tied = det["ambiguous_with"].fillna("").str.contains(e)
            print(f"| {e} | {len(det)}/{len(has)} | {named.sum()}/{len(det)} | "
                  f"{(named | tied).sum()}/{len(det)} |")
        pairs = g[g["truth"].str.contains(r"\+")]
        both = pairs[pairs.apply(lambda r: all(r.get(f"detectable_{e}") for e in
                                               r["truth"].split("+")), axis=1)]
        hit = both.apply(lambda r: set(r["truth"].split("+")) <= set(r["named"].split(",")),
                         axis=1)
        print(f"\nboth effects of a pair named: {int(hit.sum())}/{len(both)} where both are "
              "detectable")
        none = g[g["truth"] == "none"]
        print(f"false effect on elastic draws: {int((none['named'] != '').sum())}/{len(none)}")
        def wrong_not_tied(r):
            named = set(filter(None, r["named"].split(",")))
            truth = set() if r["truth"] == "none" else set(r["truth"].split("+"))
            tied = set(filter(None, str(r["ambiguous_with"] or "").split(",")))
            # a wrong effect is tied when a true effect that is not named is among the ties
            return bool(named - truth) and not ((truth - named) & tied)

        wrong = g.apply(lambda r: r["truth"] != "none" and wrong_not_tied(r), axis=1)
        print(f"a wrong effect not tied (draws with effects): {int(wrong.sum())}/"
              f"{int((g['truth'] != 'none').sum())}")
        right = g[g.apply(lambda r: r["truth"] != "none" and set(r["truth"].split("+"))
                          == set(filter(None, r["named"].split(","))), axis=1)]
        errs = {"X1d": (right["fit_x1d"] / right["x1d"] - 1).abs()}
        st = right[right["truth"].str.contains(STIFF)]
        errs["X2d"] = (st["fit_x2d"] / (st["x2_over_x1d"] * st["x1d"]) - 1).abs()
        cr = right[right["truth"].str.contains(CREEP)]
        errs["g"] = (cr["fit_g"] / cr["g"] - 1).abs()
        errs["tau"] = (cr["fit_tau_s"] / cr["tau_s"] - 1).abs()
        print("median |error| of the draws named right: " + ", ".join(
            f"{k} {100 * v.median():.1f} % (n = {len(v)})" for k, v in errs.items() if len(v)))
        if "creeping" in g and g["layers_tested"].fillna(False).astype(bool).any():
            t = g[g["layers_tested"].fillna(False).astype(bool)]
            print("which layer creeps (rows: truth, columns: answer):")
            print(pd.crosstab(t["creep_layer"], t["creeping"]).to_string())
        print(f"CPU per diagnosis: median {g['diagnosis_cpu_s'].median():.1f} s, 90th "
              f"{g['diagnosis_cpu_s'].quantile(0.9):.1f} s; FE {g['fe_cpu_s'].median():.1f} s")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--per-class", type=int, default=8)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--designs", nargs="+", default=list(DESIGNS))
    ap.add_argument("--out", default="benchmarks/out/diagnose_effects_confusion.csv")
    ap.add_argument("--summary", metavar="CSV", help="print the summary of rows already run")
    args = ap.parse_args()
    if args.summary:
        summarise(pd.read_csv(args.summary))
        return
    rng = np.random.default_rng(args.seed)
    tmp = tempfile.mkdtemp()
    jobs = []
    for i in range(args.per_class):
        for truth in CLASSES:
            effects, s = draw(rng, truth)
            for design in args.designs:
                jobs.append((design, DESIGNS[design], truth, effects, s,
                             args.seed * 10000 + len(jobs), tmp))
    start = time.perf_counter()
    rows = []
    with get_context("fork").Pool(args.workers) as pool:
        for k, row in enumerate(pool.imap_unordered(one, jobs), 1):
            rows.append(row)
            print(f"  {k}/{len(jobs)} {row['design']}: {row['truth']} -> {row.get('named')!r}"
                  f"{' ERROR ' + row['error'] if 'error' in row else ''} "
                  f"({time.perf_counter() - start:.0f} s)", flush=True)
    df = pd.DataFrame(rows)
    if "error" not in df:
        df["error"] = None
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    df.to_csv(args.out, index=False)
    summarise(df)
    print(f"\nwall {time.perf_counter() - start:.0f} s on {args.workers} workers; rows in {args.out}")


if __name__ == "__main__":
    main()
