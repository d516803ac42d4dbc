"""Single and paired effects in Cutometer time curves: named effect by effect?

:func:`effects_confusion_study` draws skins of each class (seeded; X1d log-uniform
0.03-0.12 MPa, X1h/X1d 0.01-0.3):

* ``none``: elastic (g = 1e-4, far below the 0.01 mm steps);
* ``viscoelastic_creep``: one Prony term on both layers, g 0.1-1, tau 0.1-1 s;
* ``strain_stiffening``: X2d/X1d log-uniform 2-30, no creep;
* ``pre_tension``: lambda0 1.03-1.15, no creep;
* ``viscoelastic_creep+strain_stiffening`` and ``viscoelastic_creep+pre_tension``;
* ``hypodermis_creep``: creep (g 0.3-2) in the hypodermis only: the effect is creep,
  and two apertures should tell its layer.

Each is measured by the designs of :data:`EFFECT_DESIGNS` (mode 1, 400 mbar, 2 s on /
2 s off, 2 cycles, 50 Hz): FE time solves (:func:`virtual_skin_curve`, independent of
the fast path and of the space the diagnosis reads), noise 3 µm, rounded to 0.01 mm,
then :func:`skinsuction.diagnose.diagnose_time_data`.

An effect of the truth is *detectable* when, on the noise-free curves judged with the
noisy file's sd, the model of the true effects beats the model without it by the
decision's ``|delta_bic|`` and the model without it misfits with the noise's expected
chi^2 added.  :func:`effects_confusion_summary` gives, per design: each effect's rate
named where detectable (and right or tied), both effects of a pair named, false effects
on the elastic draws, wrong effects not tied, the median errors of the draws named
right, which layer creeps against the truth, CPU per diagnosis.
"""

from __future__ import annotations

import tempfile
import time
from multiprocessing import get_context
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats

from ._time_virtual import mode1_suction, virtual_skin_curve, write_time_csv

__all__ = ["EFFECT_CLASSES", "EFFECT_DESIGNS", "draw_effects", "effects_skin",
           "diagnose_effect_draw", "effects_confusion_study", "effects_confusion_summary",
           "effects_confusion_markdown"]

CREEP, STIFF, PRE = "viscoelastic_creep", "strain_stiffening", "pre_tension"
#: The true classes drawn.
EFFECT_CLASSES = ("none", CREEP, STIFF, PRE, f"{CREEP}+{STIFF}", f"{CREEP}+{PRE}",
                  "hypodermis_creep")
#: The designs: name -> probes (mm), each measured in mode 1.
EFFECT_DESIGNS = {"mode 1, 2 mm": (2.0,), "mode 1, 2 + 8 mm": (2.0, 8.0)}


def draw_effects(rng, truth: str):
    """``(effects, skin values)`` of one draw of class ``truth`` (:data:`EFFECT_CLASSES`).

    >>> effects, s = draw_effects(np.random.default_rng(0), "hypodermis_creep")
    >>> effects, s["creep_layer"], s["x2_over_x1d"], 0.3 <= s["g"] <= 2
    (['viscoelastic_creep'], 'hypodermis', 0.0, True)
    """
    effects = ([] if truth == "none" else [CREEP] if truth == "hypodermis_creep"
               else truth.split("+"))
    s = {"x1d": 10 ** rng.uniform(np.log10(0.03), np.log10(0.12)),
         "ratio": 10 ** rng.uniform(-2, np.log10(0.3)),
         "g": 10 ** rng.uniform(-1, 0) if CREEP in effects else 1e-4,
         "tau_s": 10 ** rng.uniform(-1, 0),
         "x2_over_x1d": 10 ** rng.uniform(np.log10(2), np.log10(30)) if STIFF in effects
         else 0.0,
         "lambda0": rng.uniform(1.03, 1.15) if PRE in effects else 1.0,
         "creep_layer": ("hypodermis" if truth == "hypodermis_creep" else
                         "both" if CREEP in effects else "none")}
    if truth == "hypodermis_creep":
        s["g"] = 10 ** rng.uniform(np.log10(0.3), np.log10(2))
    return effects, s


def effects_skin(s: dict):
    """The :class:`skinsuction.model.Skin` of a draw's values."""
    from skinsuction.model import Skin
    from skinsuction.viscoelastic import Prony

    skin = Skin.two_layer(s["x1d"], s["x1d"] * s["ratio"], x2d=s["x2_over_x1d"] * s["x1d"],
                          prestretch=s["lambda0"], spectrum=Prony([s["g"]], [s["tau_s"]]))
    if s["creep_layer"] == "hypodermis":
        skin = skin.replace({"dermis.spectrum.g[0]": 1e-4})
    return skin


def diagnose_effect_draw(job) -> dict:
    """One draw, one design: FE curves, the diagnosis, the detectability; never raises
    (an FE or fit failure is the row's ``error``).

    ``job`` = ``(design, probes, truth, effects, values, seed, folder)``.
    """
    from skinsuction.diagnose import EffectFitter, Settings, diagnose_time_data
    from skinsuction.identify.time_curves import prepare_time_fit
    from skinsuction.measured import load_time_curves
    from skinsuction.space import load_space

    design, probes, truth, effects, s, seed, folder = job
    row = {"design": design, "truth": truth, "seed": seed, **s, "error": None}
    try:
        space = load_space()
        suction = mode1_suction(400.0, on_s=2.0, off_s=2.0, cycles=2)
        noisy, exact = [], []
        t0 = time.process_time()
        for k, probe in enumerate(probes):
            t, p, d, clean, _ = virtual_skin_curve(effects_skin(s), suction, probe_mm=probe,
                                                   rate_hz=50.0, seed=seed * 10 + k)
            noisy.append((probe, t, p, d))
            exact.append((probe, t, p, clean))
        row["fe_cpu_s"] = time.process_time() - t0
        data = load_time_curves(write_time_csv(Path(folder) / f"n{seed}.csv", noisy, ["FE"]))
        t0 = time.process_time()
        r = diagnose_time_data(data, space, Settings(seed=seed))
        row["diagnosis_cpu_s"] = time.process_time() - t0
        sd_um = 1e3 * float(np.mean([c.noise_sd_mm for c in data.curves]))
        # detectability on the noise-free curves, judged with the noisy file's sd
        clean = load_time_curves(write_time_csv(Path(folder) / f"c{seed}.csv", exact, ["FE"]))
        cs = Settings(seed=seed, noise_um=sd_um)
        fitter = EffectFitter(prepare_time_fit(clean, space, noise_um=sd_um), cs, [STIFF, PRE])
        full = fitter.fit(tuple(effects))
        for e in effects:
            without = fitter.fit(tuple(x for x in effects if x != e))
            dof = without.n_points - without.n_params
            misfits = dof + without.chi2 >= stats.chi2.ppf(1 - cs.alpha, dof)
            row[f"detectable_{e}"] = bool(full.bic - without.bic <= cs.delta_bic and misfits)
        cl = r.get("creep_layers") or {}
        fp = r["final"]["parameters"]
        row.update({"named": ",".join(r["effects"]), "verdict": r["verdict"],
                    "ambiguous_with": ",".join(r.get("ambiguous_with") or []),
                    "removed": ",".join(x["effect"] for x in r.get("removed") or []),
                    "creep_terms": r["creep_terms"], "noise_um": sd_um,
                    "layers_tested": bool(cl.get("tested")), "creeping": cl.get("creeping"),
                    "layers_delta_bic": cl.get("delta_bic"),
                    "g_dermis": ((cl.get("parameters") or {}).get("g_dermis") or [None])[0],
                    "g_hypodermis": ((cl.get("parameters") or {}).get("g_hypodermis")
                                     or [None])[0],
                    "fit_x1d": fp["X1d"], "fit_x2d": fp.get("X2d"),
                    "fit_lambda0": fp.get("lambda0"),
                    "fit_g": (fp.get("g") or [None])[-1],
                    "fit_tau_s": (fp.get("tau_s") or [None])[-1]})
    except Exception as err:  # noqa: BLE001 - a failed draw is recorded, not dropped
        row["error"] = f"{type(err).__name__}: {' '.join(str(err).split())[:300]}"
    return row


def effects_confusion_study(per_class: int = 10, seed: int = 0, designs=None,
                            classes=EFFECT_CLASSES, processes: int = 1,
                            progress=None) -> pd.DataFrame:
    """Every draw of every class under every design (:func:`diagnose_effect_draw`).

    Parameters
    ----------
    per_class : int
        Draws per class (each measured by every design).
    seed : int
    designs : list of str, optional
        Keys of :data:`EFFECT_DESIGNS` (default: all).
    classes : sequence of str
    processes : int
        Worker processes (fork).
    progress : callable, optional
        Called with each row as it comes.

    Returns
    -------
    pandas.DataFrame
        One row per (draw, design), failed ones with their ``error``.
    """
    jobs = draw_jobs(draw_effects, EFFECT_DESIGNS, designs, classes, per_class, seed,
                     "effects_")
    return run_jobs(diagnose_effect_draw, jobs, processes, progress)


def draw_jobs(draw, all_designs: dict, designs, classes, per_class: int, seed: int,
              prefix: str) -> list:
    """``(design, probes, truth, effects, values, seed, folder)`` per draw and design.

    ``draw(rng, truth)`` gives a draw's ``(effects, values)``; every draw is measured
    by each of ``designs`` (keys of ``all_designs``, default all), its seed unique."""
    designs = list(designs or all_designs)
    unknown = [d for d in designs if d not in all_designs]
    if unknown:
        raise ValueError(f"designs: unknown {unknown}; known: {list(all_designs)}")
    rng = np.random.default_rng(seed)
    folder = tempfile.mkdtemp(prefix=prefix)
    jobs = []
    for _ in range(int(per_class)):
        for truth in classes:
            effects, s = draw(rng, truth)
            for design in designs:
                jobs.append((design, all_designs[design], truth, effects, s,
                             seed * 10000 + len(jobs), folder))
    return jobs


def run_jobs(run, jobs: list, processes: int = 1, progress=None) -> pd.DataFrame:
    """``run(job)`` of every job (in forked workers if ``processes > 1``), by seed."""
    rows = []
    if processes > 1:
        with get_context("fork").Pool(processes) as pool:
            for row in pool.imap_unordered(run, jobs):
                rows.append(row)
                if progress:
                    progress(row)
    else:
        for job in jobs:
            rows.append(run(job))
            if progress:
                progress(rows[-1])
    return pd.DataFrame(rows).sort_values(["seed"]).reset_index(drop=True)


def _sets(r):
    named = set(filter(None, str(r["named"]).split(",")))
    truth = {"none": set(), "hypodermis_creep": {CREEP}}.get(r["truth"])
    truth = set(r["truth"].split("+")) if truth is None else truth
    tied = set(filter(None, str(r["ambiguous_with"]).split(",")))
    return named, truth, tied


def effects_confusion_summary(frame: pd.DataFrame) -> dict:
    """The rates per design (see the module docstring), JSON-able.

    Returns
    -------
    dict
        ``{design: {"draws", "effects": {effect: {"detectable", "with_effect",
        "named", "right_or_tied"}}, "pairs": [named, detectable], "false_effect":
        [count, elastic draws], "wrong_not_tied": [count, draws with effects],
        "median_error_pct": {...}, "layers": {truth: {answer: count}},
        "diagnosis_cpu_s": [median, 90th]}}`` and ``"failed"``.
    """
    ok = frame[frame["error"].isna()].copy()
    for col in ("named", "ambiguous_with"):
        ok[col] = ok[col].fillna("").astype(str)
    out = {"failed": int(len(frame) - len(ok))}
    for design, g in ok.groupby("design", sort=False):
        sets = g.apply(_sets, axis=1)
        rec = {"draws": int(len(g)), "effects": {}}
        for e in (CREEP, STIFF, PRE):
            has = g[[e in t for _, t, _ in sets]]
            col = f"detectable_{e}"
            det = has[has[col].fillna(False).astype(bool)] if col in has else has.iloc[:0]
            named = det["named"].apply(lambda x: e in x.split(",")).astype(bool)
            tied = det["ambiguous_with"].apply(lambda x: e in x.split(",")).astype(bool)
            rec["effects"][e] = {"with_effect": int(len(has)), "detectable": int(len(det)),
                                 "named": int(named.sum()),
                                 "right_or_tied": int((named | tied).sum())}
        pairs = g[[len(t) == 2 for _, t, _ in sets]]
        both = pairs[pairs.apply(lambda r: all(r.get(f"detectable_{e}") is True
                                               or r.get(f"detectable_{e}") == 1
                                               for e in _sets(r)[1]), axis=1)]
        hit = both.apply(lambda r: _sets(r)[1] <= _sets(r)[0], axis=1).astype(bool)
        rec["pairs"] = [int(hit.sum()), int(len(both))]
        none = g[g["truth"] == "none"]
        rec["false_effect"] = [int((none["named"] != "").sum()), int(len(none))]
        wrong = [bool(n - t) and not ((t - n) & tied) for n, t, tied in sets]
        with_effects = [bool(t) for _, t, _ in sets]
        rec["wrong_not_tied"] = [int(sum(w and h for w, h in zip(wrong, with_effects))),
                                 int(sum(with_effects))]
        right = g[[bool(t) and n == t for n, t, _ in sets]]
        errs = {"X1d": (right["fit_x1d"] / right["x1d"] - 1).abs()}
        st = right[right["truth"].str.contains(STIFF)]
        errs["X2d"] = (st["fit_x2d"].astype(float) / (st["x2_over_x1d"] * st["x1d"]) - 1).abs()
        cr = right[[CREEP in _sets(r)[1] for _, r in right.iterrows()]]
        errs["g"] = (cr["fit_g"].astype(float) / cr["g"] - 1).abs()
        errs["tau"] = (cr["fit_tau_s"].astype(float) / cr["tau_s"] - 1).abs()
        rec["median_error_pct"] = {k: [float(100 * v.median()), int(len(v))]
                                   for k, v in errs.items() if len(v)}
        tested = g[g["layers_tested"].fillna(False).astype(bool)] if "layers_tested" in g \
            else g.iloc[:0]
        rec["layers"] = {str(k): {str(a): int(n) for a, n in v.items()}
                         for k, v in pd.crosstab(tested["creep_layer"],
                                                 tested["creeping"]).iterrows()} \
            if len(tested) else {}
        cpu = g["diagnosis_cpu_s"].astype(float)
        rec["diagnosis_cpu_s"] = [float(cpu.median()), float(cpu.quantile(0.9))]
        out[design] = rec
    return out


def effects_confusion_markdown(frame: pd.DataFrame) -> str:
    """The summary as Markdown (tables per design)."""
    s = effects_confusion_summary(frame)
    lines = ["# Single and paired effects in time curves", "",
             f"{len(frame)} draws, {s['failed']} failed (FE or fit, recorded in the table)."]
    for design, rec in s.items():
        if design == "failed":
            continue
        lines += ["", f"## {design} ({rec['draws']} draws)", "",
                  "| effect | detectable | named where detectable | right or tied |",
                  "|---|---|---|---|"]
        for e, v in rec["effects"].items():
            lines.append(f"| {e} | {v['detectable']}/{v['with_effect']} | "
                         f"{v['named']}/{v['detectable']} | {v['right_or_tied']}/{v['detectable']} |")
        lines += ["", f"- both effects of a pair named: {rec['pairs'][0]}/{rec['pairs'][1]} "
                      "where both are detectable",
                  f"- a false effect on the elastic draws: {rec['false_effect'][0]}/"
                  f"{rec['false_effect'][1]}",
                  f"- a wrong effect not tied: {rec['wrong_not_tied'][0]}/"
                  f"{rec['wrong_not_tied'][1]} draws with effects",
                  "- median |error| of the draws named right: " + ", ".join(
                      f"{k} {v[0]:.1f} % (n = {v[1]})" for k, v in
                      rec["median_error_pct"].items()),
                  f"- CPU per diagnosis: median {rec['diagnosis_cpu_s'][0]:.1f} s, 90th "
                  f"{rec['diagnosis_cpu_s'][1]:.1f} s"]
        if rec["layers"]:
            answers = sorted({a for v in rec["layers"].values() for a in v})
            lines += ["", "Which layer creeps (rows: truth, columns: answer):", "",
                      "| truth | " + " | ".join(answers) + " |",
                      "|---|" + "---|" * len(answers)]
            for truth, v in rec["layers"].items():
                lines.append(f"| {truth} | " + " | ".join(str(v.get(a, 0)) for a in answers)
                             + " |")
    return "\n".join(lines) + "\n"
