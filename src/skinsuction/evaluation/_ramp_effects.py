"""Single and paired effects in pressure ramps: named effect by effect?

:func:`ramp_effects_study` draws skins of each class of :data:`RAMP_CLASSES`
(seeded; X1d log-uniform 0.03-0.12 MPa, X1h/X1d 0.01-0.3, the paper's 1 mm layers
unless the hypodermis is the effect):

* ``none``: neo-Hookean;
* ``strain_stiffening``: X2d/X1d log-uniform 2-30;
* ``pre_tension``: lambda0 1.03-1.15;
* ``hypodermis_thickness``: t_h log-uniform 2-6 mm;
* ``strain_stiffening+pre_tension`` and ``strain_stiffening+hypodermis_thickness``.

Each is measured by the designs of :data:`RAMP_DESIGNS` (a ramp on two probes to a
suction drawn log-uniform in 100-500 mbar, 51 points, 2 µm noise): FE curves
(:func:`skinsuction.evaluation.virtual_experiment`, independent of the spaces the
diagnosis reads), then :func:`skinsuction.diagnose.diagnose_file` with the single
causes' spaces and the pair spaces shipped with the package.

An effect of the truth is *detectable* when, on the noise-free curves judged with
the noisy file's sd, the model of the true effects beats the model without it by
the decision's ``|delta_bic|`` (the single causes' and the pairs' fits of that
diagnosis).  :func:`ramp_effects_summary` gives, per design: each effect's rate
named where detectable (right or tied) beside its attribution ceiling (the mean over
those draws of Phi(sqrt(g)/2), g the noise-free chi^2 gap to the best model that
swaps the effect for another), both effects of a pair named, false effects on the
neo-Hookean draws, wrong effects not tied, the median errors of the draws named
right, CPU per diagnosis.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pandas as pd

from ._effects import draw_jobs, run_jobs

__all__ = ["RAMP_CLASSES", "RAMP_DESIGNS", "draw_ramp_effects", "diagnose_ramp_draw",
           "ramp_effects_study", "ramp_effects_summary", "ramp_effects_markdown"]

STIFF, PRE, THICK = "strain_stiffening", "pre_tension", "hypodermis_thickness"
#: The true classes drawn.
RAMP_CLASSES = ("none", STIFF, PRE, THICK, f"{STIFF}+{PRE}", f"{STIFF}+{THICK}")
#: The designs: name -> probes (mm), each a ramp.
RAMP_DESIGNS = {"ramp, 2 + 6 mm": (2.0, 6.0), "ramp, 4 + 8 mm": (4.0, 8.0)}
#: The model keyword and truth column of each effect.
KEYWORDS = {STIFF: ("x2d", "x2d_mpa"), PRE: ("prestretch", "lambda0"), THICK: ("t_h", "t_h_mm")}


def draw_ramp_effects(rng, truth: str) -> tuple:
    """``(effects, values)`` of one draw of class ``truth`` (:data:`RAMP_CLASSES`).

    >>> effects, s = draw_ramp_effects(np.random.default_rng(0), "strain_stiffening+pre_tension")
    >>> effects, 100 <= s["p_max_mbar"] <= 500, s["t_h_mm"]
    (['strain_stiffening', 'pre_tension'], True, 1.0)
    """
    effects = [] if truth == "none" else truth.split("+")
    x1d = 10 ** rng.uniform(np.log10(0.03), np.log10(0.12))
    s = {"x1d": x1d, "ratio": 10 ** rng.uniform(-2, np.log10(0.3)),
         "x2d_mpa": x1d * 10 ** rng.uniform(np.log10(2), np.log10(30)) if STIFF in effects
         else 0.0,
         "lambda0": rng.uniform(1.03, 1.15) if PRE in effects else 1.0,
         "t_h_mm": 10 ** rng.uniform(np.log10(2), np.log10(6)) if THICK in effects else 1.0,
         "p_max_mbar": float(np.round(10 ** rng.uniform(2, np.log10(500)), -1))}
    return effects, s


def _keywords(s: dict) -> dict:
    return {kw: s[col] for kw, col in KEYWORDS.values()}


def _detectable(clean: dict, effects: list, delta_bic: float) -> dict:
    """Each true effect: does the model of the true effects beat the one without it?"""
    single = {c["cause"]: c["bic"] for c in clean["candidates"]}
    pairs = {frozenset(o["effects"]): o["bic"] for o in clean["second_effect"]["options"]}
    base = clean["baseline"]["bic"]
    out = {}
    for e in effects:
        if len(effects) == 1:
            full, without = single.get(e), base
        else:
            other = next(x for x in effects if x != e)
            full, without = pairs.get(frozenset(effects)), single.get(other)
        out[e] = bool(full is not None and without is not None and full - without <= delta_bic)
    return out


def _ceilings(clean: dict, effects: list) -> dict:
    """Each true effect's attribution ceiling on the noise-free curves: Phi(sqrt(g) / 2),
    g the chi^2 gap to the best model of as many effects that swaps it for another
    (:func:`skinsuction.evaluation.attribution_ceiling`); NaN where none was fitted."""
    from ._rates import attribution_ceiling

    chi2 = {frozenset([c["cause"]]): c["fit"]["chi2"] for c in clean["candidates"]}
    chi2.update({frozenset(o["effects"]): o["fit"]["chi2"]
                 for o in clean["second_effect"]["options"]})
    truth = frozenset(effects)
    out = {}
    for e in effects:
        rivals = [v for k, v in chi2.items() if len(k) == len(truth) and e not in k
                  and truth - {e} <= k]
        out[e] = (float(attribution_ceiling(min(rivals) - chi2[truth]))
                  if rivals and truth in chi2 else float("nan"))
    return out


def diagnose_ramp_draw(job) -> dict:
    """One draw, one design: FE curves, the diagnosis, the detectability; never raises
    (an FE or fit failure is the row's ``error``).

    ``job`` = ``(design, probes, truth, effects, values, seed, folder)``.
    """
    from skinsuction.diagnose import Settings, diagnose_file
    from skinsuction.space import SHIPPED_SPACE_DIR, pairs_for, read_ray_spaces

    from ._virtual import virtual_experiment, write_csv

    design, probes, truth, effects, s, seed, folder = job
    row = {"design": design, "truth": truth, "seed": seed, **s, "error": None}
    try:
        spaces = read_ray_spaces(SHIPPED_SPACE_DIR)
        pairs = pairs_for(None, spaces["neo_hookean"].spec)
        p = np.linspace(0.0, s["p_max_mbar"], 51)
        t0 = time.process_time()
        ve = virtual_experiment(s["x1d"], s["x1d"] * s["ratio"], noise_um=2.0, seed=seed,
                                probes_mm=probes, pressures_mbar=p, keywords=_keywords(s))
        row["fe_cpu_s"] = time.process_time() - t0
        noisy = write_csv(ve, Path(folder) / f"n{seed}.csv")
        t0 = time.process_time()
        r = diagnose_file(noisy, None, Settings(seed=seed), spaces=spaces, pairs=pairs,
                          on_demand=False)
        row["diagnosis_cpu_s"] = time.process_time() - t0
        sd_um = float(r["noise_um"])
        ve.curves = {(q, 0): c for q, c in ve.clean.items()}
        clean = diagnose_file(write_csv(ve, Path(folder) / f"c{seed}.csv"), None,
                              Settings(seed=seed, noise_um=sd_um), spaces=spaces, pairs=pairs,
                              on_demand=False)
        for e, ok in _detectable(clean, effects, Settings().delta_bic).items():
            row[f"detectable_{e}"] = ok
        for e, c in _ceilings(clean, effects).items():
            row[f"ceiling_{e}"] = c
        final = (r.get("extended") or {}).get("parameters") or r["baseline"]["parameters"]
        ci = (r.get("extended") or {}).get("intervals") or r["baseline"].get("intervals") or {}
        for key, col in (("X1d", "x1d"), ("X2d", "x2d"), ("lambda0", "lambda0"),
                         ("t_h", "t_h")):
            iv = ci.get(key) if isinstance(ci.get(key), dict) else {}
            row[f"ci_{col}_lower"], row[f"ci_{col}_upper"] = iv.get("lower"), iv.get("upper")
        # a tied pair stands for its two causes
        tied = sorted({c for m in r.get("ambiguous_with") or [] for c in m.split("_and_")})
        row.update({"named": ",".join(r["effects"]), "verdict": r["verdict"],
                    "ambiguous_with": ",".join(tied),
                    "second_tried": bool(r["second_effect"]["tried"]), "noise_um": sd_um,
                    "fit_x1d": final["X1d"], "fit_x2d": final.get("X2d"),
                    "fit_lambda0": final.get("lambda0"), "fit_t_h": final.get("t_h")})
    except Exception as err:  # noqa: BLE001 - a failed draw is recorded, not dropped
        row["error"] = f"{type(err).__name__}: {' '.join(str(err).split())[:300]}"
    return row


def ramp_effects_study(per_class: int = 10, seed: int = 0, designs=None,
                       classes=RAMP_CLASSES, processes: int = 1,
                       progress=None) -> pd.DataFrame:
    """Every draw of every class under every design (:func:`diagnose_ramp_draw`).

    Parameters
    ----------
    per_class : int
        Draws per class (each measured by every design).
    seed : int
    designs : list of str, optional
        Keys of :data:`RAMP_DESIGNS` (default: all).
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
    jobs = draw_jobs(draw_ramp_effects, RAMP_DESIGNS, designs, classes, per_class, seed,
                     "ramp_effects_")
    return run_jobs(diagnose_ramp_draw, jobs, processes, progress)


def _sets(r):
    named = set(filter(None, str(r["named"]).split(",")))
    truth = set() if r["truth"] == "none" else set(r["truth"].split("+"))
    tied = set(filter(None, str(r.get("ambiguous_with") or "").split(",")))
    return named, truth, tied


def ramp_effects_summary(frame: pd.DataFrame) -> dict:
    """The rates per design (see the module docstring), JSON-able; the structure of
    :func:`skinsuction.evaluation.effects_confusion_summary`.

    Returns
    -------
    dict
        ``{design: {"draws", "effects": {effect: {"with_effect", "detectable",
        "named", "right_or_tied"}}, "pairs": [both named, both detectable],
        "false_effect": [count, neo-Hookean draws], "wrong_not_tied": [count, draws
        with effects], "median_error_pct": {parameter: [median, draws]},
        "diagnosis_cpu_s": [median, 90th]}}`` and ``"failed"``.
    """
    ok = frame[frame["error"].isna()].copy()
    for col in ("named", "ambiguous_with"):
        ok[col] = ok[col].fillna("").astype(str)
    out = {"failed": int(len(frame) - len(ok))}
    for design, g in ok.groupby("design", sort=False):
        sets = [_sets(r) for _, r in g.iterrows()]
        rec = {"draws": int(len(g)), "effects": {}}
        for e in KEYWORDS:
            col = f"detectable_{e}"
            rows = [(r, n, tied) for (_, r), (n, t, tied) in zip(g.iterrows(), sets) if e in t]
            det = [(n, tied) for r, n, tied in rows if col in r and r[col] is True
                   or r.get(col) == 1]
            ceil = [r.get(f"ceiling_{e}") for r, _, _ in rows
                    if r.get(col) in (True, 1)]
            ceil = [c for c in ceil if c is not None and np.isfinite(c)]
            rec["effects"][e] = {"with_effect": len(rows), "detectable": len(det),
                                 "named": sum(e in n for n, _ in det),
                                 "right_or_tied": sum(e in n or e in tied for n, tied in det),
                                 "ceiling": float(np.mean(ceil)) if ceil else None}
        both = [(n, t) for (_, r), (n, t, _) in zip(g.iterrows(), sets)
                if len(t) == 2 and all(r.get(f"detectable_{e}") in (True, 1) for e in t)]
        rec["pairs"] = [sum(t <= n for n, t in both), len(both)]
        rec["false_effect"] = [sum(bool(n) for n, t, _ in sets if not t),
                               sum(not t for _, t, _ in sets)]
        rec["wrong_not_tied"] = [sum(bool(n - t) and not ((t - n) & tied)
                                     for n, t, tied in sets if t), sum(bool(t) for _, t, _ in sets)]
        right = g[[bool(t) and n == t for n, t, _ in sets]]
        errs = {"X1d": (right["fit_x1d"] / right["x1d"] - 1).abs()}
        for e, key, fit, true in ((STIFF, "X2d", "fit_x2d", "x2d_mpa"),
                                  (PRE, "lambda0-1", "fit_lambda0", "lambda0"),
                                  (THICK, "t_h", "fit_t_h", "t_h_mm")):
            sub = right[right["truth"].str.contains(e)]
            f, t = sub[fit].astype(float), sub[true].astype(float)
            errs[key] = ((f - 1) / (t - 1) - 1).abs() if e == PRE else (f / t - 1).abs()
        rec["median_error_pct"] = {k: [float(100 * v.median()), int(len(v))]
                                   for k, v in errs.items() if len(v)}
        rec["coverage"] = _coverage(right)
        cpu = g["diagnosis_cpu_s"].astype(float)
        rec["diagnosis_cpu_s"] = [float(cpu.median()), float(cpu.quantile(0.9))]
        out[design] = rec
    return out


def _coverage(right: pd.DataFrame) -> dict:
    """``{parameter: [covered, draws]}``: the 95 % intervals of the draws named right
    that hold the truth (X1d always; each effect's parameter where it is true)."""
    out = {}
    for col, true, effect in (("x1d", "x1d", None), ("x2d", "x2d_mpa", STIFF),
                              ("lambda0", "lambda0", PRE), ("t_h", "t_h_mm", THICK)):
        lo, hi = f"ci_{col}_lower", f"ci_{col}_upper"
        if lo not in right:
            continue
        sub = right if effect is None else right[right["truth"].str.contains(effect)]
        sub = sub[sub[lo].notna() & sub[hi].notna()]
        if len(sub):
            inside = (sub[lo].astype(float) <= sub[true]) & (sub[true] <= sub[hi].astype(float))
            out[col] = [int(inside.sum()), int(len(sub))]
    return out


def ramp_effects_markdown(frame: pd.DataFrame) -> str:
    """The summary as Markdown: one table per design."""
    s = ramp_effects_summary(frame)
    lines = ["# Single and paired effects in ramps", ""]
    for design, rec in s.items():
        if design == "failed":
            continue
        lines += [f"## {design} ({rec['draws']} draws)", "",
                  "| effect | draws with it | detectable | named | named or tied | ceiling |",
                  "|---|---|---|---|---|---|"]
        for e, v in rec["effects"].items():
            ceil = "–" if v["ceiling"] is None else f"{100 * v['ceiling']:.0f} %"
            lines.append(f"| {e} | {v['with_effect']} | {v['detectable']} | {v['named']} | "
                         f"{v['right_or_tied']} | {ceil} |")
        err = ", ".join(f"{k} {v[0]:.1f} % ({v[1]})" for k, v in rec["median_error_pct"].items())
        lines += ["", f"- pairs, both effects named where both are detectable: "
                      f"{rec['pairs'][0]}/{rec['pairs'][1]}",
                  f"- a false effect on a neo-Hookean draw: {rec['false_effect'][0]}/"
                  f"{rec['false_effect'][1]}",
                  f"- a wrong effect, not tied: {rec['wrong_not_tied'][0]}/"
                  f"{rec['wrong_not_tied'][1]}",
                  f"- median errors of the draws named right: {err or 'none'}",
                  "- their 95 % intervals holding the truth: " + (", ".join(
                      f"{k} {v[0]}/{v[1]}" for k, v in rec.get("coverage", {}).items())
                      or "none"),
                  f"- CPU per diagnosis: median {rec['diagnosis_cpu_s'][0]:.0f} s, 90th "
                  f"percentile {rec['diagnosis_cpu_s'][1]:.0f} s", ""]
    lines.append(f"Failed draws: {s['failed']}.")
    return "\n".join(lines) + "\n"
