"""The identification runs of the paper's Figures 4, 4b, 7 and 8, and their summaries."""

from __future__ import annotations

import logging
import math
import time

import numpy as np
import pandas as pd

log = logging.getLogger(__name__)

from skinsuction.identify import identify_repeated

from ._setup import (
    OBJECTIVES,
    StudySetup,
    build_objective,
    case_seed,
    load_setup,
    scale_free_setup,
    setup_from_files,
)

def runs_frame(rep, *, to_moduli=None, **labels) -> pd.DataFrame:
    """One row per identification of a :class:`RepeatedIdentification`.

    ``to_moduli`` maps the runs' candidates to (X1d, X1h) in MPa (the
    objective's ``to_moduli``; default: they are moduli, as on a grid space).
    """
    r = rep.results
    x = rep.estimates if to_moduli is None else to_moduli(rep.estimates)
    frame = pd.DataFrame({
        "repeat": np.arange(len(r)),
        "x1d": x[:, 0],
        "x1h": x[:, 1],
        "E": rep.E,
        "E_unit": [x.E_unit for x in r],
        "cost": [x.cost for x in r],
        "iterations": rep.iterations,
        "n_evaluations": [x.n_evaluations for x in r],
        "seconds": [x.seconds for x in r],
        "converged": rep.converged,
    })
    for i, (k, v) in enumerate(labels.items()):
        frame.insert(i, k, v)
    return frame


def _success(x1d, x1h, target, tol):
    t = np.asarray(target, dtype=float)
    return (np.abs(np.asarray(x1d) / t[0] - 1) <= tol) & (np.abs(np.asarray(x1h) / t[1] - 1) <= tol)


def summarise_runs(runs: pd.DataFrame, target, by=("source", "objective"),
                   success_tolerance: float = 0.01) -> pd.DataFrame:
    """Per case: estimates (median, mean, spread), errors in % of the truth, success.

    ``x1d_error_mean_pct`` is the relative error of the mean estimate,
    ``x1d_error_max_pct`` the largest |relative error| over the runs, and
    ``success_fraction`` the fraction of runs with both moduli within
    ``success_tolerance`` of the truth.
    """
    target = np.asarray(target, dtype=float)
    rows = []
    for key, g in runs.groupby(list(by), sort=True):
        key = key if isinstance(key, tuple) else (key,)
        row = dict(zip(by, key))
        row["runs"] = len(g)
        for i, name in enumerate(("x1d", "x1h")):
            x = g[name].to_numpy(float)
            rel = x / target[i] - 1
            row[f"{name}_true"] = target[i]
            row[f"{name}_median"] = float(np.median(x))
            row[f"{name}_mean"] = float(np.mean(x))
            row[f"{name}_std"] = float(np.std(x, ddof=1)) if len(x) > 1 else 0.0
            row[f"{name}_min"] = float(np.min(x))
            row[f"{name}_max"] = float(np.max(x))
            row[f"{name}_error_mean_pct"] = 100 * float(np.mean(x) / target[i] - 1)
            row[f"{name}_error_median_pct"] = 100 * float(np.median(x) / target[i] - 1)
            row[f"{name}_error_max_pct"] = 100 * float(np.max(np.abs(rel)))
        row["success_fraction"] = float(np.mean(
            _success(g["x1d"], g["x1h"], target, success_tolerance)))
        if "E" in g:
            row["E_median"] = float(g["E"].median())
            row["E_unit"] = g["E_unit"].iloc[0] if "E_unit" in g else ""
        for col in ("iterations", "n_evaluations", "seconds"):
            if col in g:
                row[f"{col}_median"] = float(g[col].median())
        if "converged" in g:
            row["converged_fraction"] = float(g["converged"].mean())
        rows.append(row)
    return pd.DataFrame(rows)


def _repeat(setup, kind, source, repeats, seed, alpha=0.5, labels=None):
    objective = build_objective(setup, kind, source, alpha)
    rep = identify_repeated(objective, repeats=repeats, seed=case_seed(seed, source, kind, alpha),
                            **setup.window_focusing)
    frame = runs_frame(rep, to_moduli=objective.to_moduli, source=source, objective=kind,
                       **(labels or {}))
    log.info("%s %s%s: %d runs, median (%.6g, %.6g), median %g iterations", source, kind,
             f" alpha={alpha:g}" if kind == "weighted" else "", repeats,
             frame["x1d"].median(), frame["x1h"].median(), np.median(rep.iterations))
    return frame


def single_probe_study(setup: StudySetup, *, repeats=100, seed=0, sources=None) -> pd.DataFrame:
    """Figure 4: ``repeats`` identifications with the 6 mm and with the 2 mm probe alone.

    Returns the runs (see :func:`runs_frame`), columns ``source, objective, ...``.
    """
    frames = [
        _repeat(setup, kind, source, repeats, seed)
        for source in (sources or setup.sources)
        for kind in ("single_6mm", "single_2mm")
    ]
    return pd.concat(frames, ignore_index=True)


def alpha_sweep(setup: StudySetup, alphas, *, repeats=100, seed=0, sources=None) -> pd.DataFrame:
    """Figure 7: ``repeats`` identifications of the weighted objective (eq. 10) per alpha."""
    frames = []
    for source in sources or setup.sources:
        for a in alphas:
            frames.append(_repeat(setup, "weighted", source, repeats, seed, alpha=float(a),
                                  labels={"alpha": float(a)}))
    return pd.concat(frames, ignore_index=True)


def alpha_threshold(summary: pd.DataFrame, min_success: float = 0.95) -> pd.DataFrame:
    """Per source: the largest alpha up to which every alpha identifies in >= ``min_success``.

    ``summary`` is :func:`summarise_runs` of :func:`alpha_sweep` by
    ``(source, alpha)``.  Also gives the alphas at which every run succeeded.
    """
    rows = []
    for source, g in summary.groupby("source", sort=True):
        g = g.sort_values("alpha")
        ok = g["success_fraction"].to_numpy() >= min_success
        a = g["alpha"].to_numpy(float)
        n_ok = int(np.argmin(ok)) if not ok.all() else len(ok)
        rows.append({
            "source": source,
            "min_success": min_success,
            "last_alpha_ok_from_0": float(a[n_ok - 1]) if n_ok else math.nan,
            "first_alpha_failing": float(a[n_ok]) if n_ok < len(a) else math.nan,
            "alphas_all_runs_succeed": " ".join(
                f"{x:g}" for x in a[g["success_fraction"].to_numpy() >= 1.0]),
            "alpha_best_x1h_error": float(a[np.argmin(np.abs(g["x1h_error_median_pct"]))]),
        })
    return pd.DataFrame(rows)


def ratio_study(setup: StudySetup, *, repeats=100, seed=0, sources=None) -> pd.DataFrame:
    """Figure 8: ``repeats`` identifications of the ratio objective (eqs. 11-12)."""
    return pd.concat(
        [_repeat(setup, "ratio", source, repeats, seed) for source in (sources or setup.sources)],
        ignore_index=True,
    )



def cost_landscape(setup: StudySetup, *, source="fe", points=151, alpha=0.5,
                   objectives=("single_2mm", "single_6mm", "weighted", "ratio")) -> pd.DataFrame:
    """Figure 4b: E (eq. 7) of each objective on a log-spaced (X1d, X1h) grid.

    The grid spans the common bounds of the spaces, ``points`` values per axis,
    log-spaced, with the test point added to both axes.  Columns
    ``objective, x1d, x1h, cost, E, E_unit`` (E = +inf where the space is not
    usable).
    """
    lo = np.max([s.lower for s in setup.spaces.values()], axis=0)
    hi = np.min([s.upper for s in setup.spaces.values()], axis=0)
    axes = []
    for i in range(2):
        a = np.geomspace(lo[i], hi[i], int(points))
        a[0], a[-1] = lo[i], hi[i]  # exactly on the bounds (round-off)
        if lo[i] <= setup.target[i] <= hi[i]:
            a = np.unique(np.append(a, setup.target[i]))
        axes.append(a)
    xd, xh = np.meshgrid(*axes, indexing="ij")
    cand = np.column_stack([xd.ravel(), xh.ravel()])
    frames = []
    for kind in objectives:
        obj = build_objective(setup, kind, source, alpha)
        j = np.asarray(obj(cand), dtype=float)
        frames.append(pd.DataFrame({
            "objective": kind, "x1d": cand[:, 0], "x1h": cand[:, 1], "cost": j,
            "E": obj.error(j), "E_unit": obj.error_unit,
        }))
    return pd.concat(frames, ignore_index=True)


def _line_max(g, axis, value):
    """Largest finite E on the grid line ``axis == value`` (the other modulus varies)."""
    line = g[np.isclose(g[axis], value, rtol=1e-12)]["E"].to_numpy(float)
    line = line[np.isfinite(line)]
    return float(line.max()) if line.size else math.nan


def landscape_summary(landscape: pd.DataFrame, target, factor: float = 2.0) -> pd.DataFrame:
    """Per objective: grid minimum, E at the target, and the valley extent.

    The valley is the set of grid points with ``E <= factor * E_min``; its X1d
    and X1h ranges (as ratios max/min) tell how well each modulus is determined
    by the objective (for a curve inside the interpolated space E_min is about
    0 and the valley shrinks to the grid point nearest the truth).
    ``E_max_along_x1h_at_true_x1d`` is the largest E over the X1h range with
    X1d at the truth (how much a wrong X1h costs), ``E_max_along_x1d_at_true_x1h``
    the same over X1d; their ratio ``x1h_to_x1d_sensitivity`` is small when the
    objective hardly sees the hypodermis.
    """
    t = np.asarray(target, dtype=float)
    rows = []
    for kind, g in landscape.groupby("objective", sort=False):
        e = g["E"].to_numpy(float)
        k = int(np.nanargmin(np.where(np.isfinite(e), e, np.nan)))
        at_t = np.isclose(g["x1d"], t[0], rtol=1e-12) & np.isclose(g["x1h"], t[1], rtol=1e-12)
        e_t = float(g.loc[at_t, "E"].iloc[0]) if at_t.any() else math.nan
        level = factor * e[k]
        valley = g[e <= level]
        rows.append({
            "objective": kind,
            "E_unit": g["E_unit"].iloc[0],
            "x1d_at_minimum": float(g["x1d"].iloc[k]),
            "x1h_at_minimum": float(g["x1h"].iloc[k]),
            "E_minimum": float(e[k]),
            "E_at_target": e_t,
            "valley_level": level,
            "valley_x1d_min": float(valley["x1d"].min()),
            "valley_x1d_max": float(valley["x1d"].max()),
            "valley_x1h_min": float(valley["x1h"].min()),
            "valley_x1h_max": float(valley["x1h"].max()),
            "valley_x1d_ratio": float(valley["x1d"].max() / valley["x1d"].min()),
            "valley_x1h_ratio": float(valley["x1h"].max() / valley["x1h"].min()),
            "E_max_along_x1h_at_true_x1d": _line_max(g, "x1d", t[0]),
            "E_max_along_x1d_at_true_x1h": _line_max(g, "x1h", t[1]),
            "fraction_not_usable": float(np.mean(~np.isfinite(e))),
        })
    out = pd.DataFrame(rows)
    out["x1h_to_x1d_sensitivity"] = (out["E_max_along_x1h_at_true_x1d"]
                                     / out["E_max_along_x1d_at_true_x1h"])
    return out


#: Studies of :func:`write_runs`.
RUN_STUDIES = ("single_probe", "alpha_sweep", "ratio")


def write_runs(study: str, space_path, test_curves_path, out_csv, settings: dict,
               alphas=None) -> pd.DataFrame:
    """Run one of :data:`RUN_STUDIES` (Figures 4, 7, 8) and write its runs as CSV."""
    from skinsuction._files import write_table

    setup = setup_from_files(space_path, test_curves_path, settings)
    common = {"repeats": int(settings.get("repeats", 100)), "seed": int(settings.get("seed", 0))}
    t0 = time.perf_counter()
    if study == "single_probe":
        runs = single_probe_study(setup, **common)
    elif study == "alpha_sweep":
        runs = alpha_sweep(setup, alphas if alphas is not None else np.linspace(0, 1, 11), **common)
    elif study == "ratio":
        runs = ratio_study(setup, **common)
    else:
        raise ValueError(f"unknown study {study!r}; choose among {RUN_STUDIES}")
    log.info("%s: %d identifications in %.1f s", study, len(runs), time.perf_counter() - t0)
    write_table(runs, out_csv)
    return runs


def compare_spaces(setups: dict, *, objectives=tuple(OBJECTIVES), repeats=100, seed=0,
                   alpha=0.5, source="fe", success_tolerance=0.01):
    """The same identifications on several spaces: ``(runs, summary)``.

    ``setups`` maps a space's name to its :class:`StudySetup`; every objective of
    :data:`OBJECTIVES` is run ``repeats`` times on the ``source`` curves with the
    same seeds on every space, and each run is also polished by bounded least
    squares (:func:`skinsuction.identify.polish`, what ``skinsuction identify``
    does to its estimate).  The summary has one row per (space, objective,
    method): median errors in % of the truth, the success rate (both moduli within
    ``success_tolerance``), iterations and milliseconds per identification.
    """
    from skinsuction.identify import polish

    frames = []
    for name, setup in setups.items():
        for kind in objectives:
            obj = build_objective(setup, kind, source, alpha)
            rep = identify_repeated(obj, repeats=repeats, seed=case_seed(seed, source, kind, alpha),
                                    **setup.window_focusing)
            wf = runs_frame(rep, to_moduli=obj.to_moduli, space=name, objective=kind,
                            method="window focusing")
            t0 = time.perf_counter()
            polished = np.array([polish(obj, t) for t in rep.estimates])
            per_run = (time.perf_counter() - t0) / len(polished)
            pol = wf.copy()
            pol["method"] = "window focusing + polish"
            pol[["x1d", "x1h"]] = obj.to_moduli(polished)
            pol["seconds"] = wf["seconds"] + per_run
            frames += [wf, pol]
            log.info("%s, %s: median X1d %.6g (WF) / %.6g (polished)", name, kind,
                     wf["x1d"].median(), pol["x1d"].median())
    runs = pd.concat(frames, ignore_index=True)
    target = next(iter(setups.values())).target
    summary = summarise_runs(runs, target, by=("space", "objective", "method"),
                             success_tolerance=success_tolerance)
    summary["ms_per_identification"] = 1e3 * summary["seconds_median"]
    order = {k: i for i, k in enumerate(objectives)}
    summary = summary.sort_values(["objective", "method", "space"],
                                  key=lambda c: c.map(order) if c.name == "objective" else c,
                                  kind="stable")
    return runs, summary.reset_index(drop=True)


def write_space_comparison(paper_space, scale_free_dir, test_curves_path, csv, markdown,
                           runs_csv, settings: dict) -> pd.DataFrame:
    """Paper grid vs scale-free space on the honest test curve: the workflow's table."""
    from skinsuction.figures.tables import markdown_table, write_markdown
    from skinsuction._files import write_table

    target = (settings["target"]["x1d"], settings["target"]["x1h"])
    bottom = settings.get("bottom", "fixed")
    wf = settings.get("window_focusing")
    setups = {
        "paper grid": load_setup(paper_space, test_curves_path, target=target, bottom=bottom,
                                 window_focusing=wf),
        "scale-free": scale_free_setup(scale_free_dir, test_curves_path, target=target,
                                       bottom=bottom, window_focusing=wf),
    }
    runs, summary = compare_spaces(setups, repeats=int(settings.get("repeats", 100)),
                                   seed=int(settings.get("seed", 0)),
                                   alpha=float(settings.get("alpha", 0.5)),
                                   success_tolerance=float(settings.get("success_tolerance",
                                                                        0.01)))
    write_table(runs, runs_csv)
    write_table(summary, csv)
    cols = ["objective", "method", "space", "x1d_error_median_pct", "x1h_error_median_pct",
            "x1d_error_max_pct", "x1h_error_max_pct", "success_fraction",
            "iterations_median", "ms_per_identification"]
    write_markdown(markdown, "Paper grid vs scale-free space, honest test curve", [
        (f"Test point X1d = {target[0]:g}, X1h = {target[1]:g} MPa: direct FE curves (same "
         f"mesh and pressures as the spaces), {int(settings.get('repeats', 100))} window "
         "focusing identifications per case with the same seeds on both spaces. Errors in % "
         "of the truth; success: both moduli within "
         f"{100 * float(settings.get('success_tolerance', 0.01)):g} %.", summary[cols]),
    ])
    log.info("space comparison:\n%s", markdown_table(summary[cols]))
    return summary
