"""The identification studies of the paper (sections 3.2-3.3) and beyond.

Each function here is what one workflow rule runs (rule -> thin script -> one
function of this module), on one simulated space and the test point of the
paper, X1d = 0.0055 MPa, X1h = 0.00041 MPa:

* :func:`make_test_curves` -- the curves to identify, in two variants
  (:data:`SOURCES`): ``fe``, a direct FE run at the test point (honest: the
  test point is off the grid, so the interpolated space does not contain this
  curve exactly), and ``space``, the curve taken from the interpolated space
  (the paper's variant, "extracting a simulated curve from the database");
* :func:`single_probe_study` -- Figure 4, 100 identifications per probe;
* :func:`cost_landscape` -- Figure 4b, log E over (X1d, X1h) per objective;
* :func:`alpha_sweep` -- Figure 7, the weighted objective against alpha;
* :func:`ratio_study` -- Figure 8, the ratio objective;
* :func:`timing_study` -- iterations and seconds per identification;
* :func:`optimiser_comparison` -- window focusing against scipy's
  ``least_squares`` from random starts and ``differential_evolution``, and
  (from :func:`fe_in_the_loop`) least squares with the FE model in the loop.

Objectives are named by :data:`OBJECTIVES`.  An identification *succeeds* if
both moduli are within ``success_tolerance`` (default 1 %) of the truth.

Examples
--------
>>> from skinsuction.identify import analytic_surrogate_space
>>> from skinsuction.space import evaluate
>>> spaces = {p: analytic_surrogate_space(p) for p in (2.0, 6.0)}
>>> curves = {"space": {p: (s.pressure_mbar, evaluate(s, [TARGET])[0])
...                     for p, s in spaces.items()}}
>>> setup = StudySetup(spaces, curves)
>>> runs = single_probe_study(setup, repeats=3, seed=0, sources=["space"])
>>> summary = summarise_runs(runs, TARGET, ["source", "objective"])
>>> summary[["objective", "success_fraction"]].values.tolist()
[['single_2mm', 1.0], ['single_6mm', 1.0]]
"""

from __future__ import annotations

import logging
import math
import time
import zlib
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ._baselines import differential_evolution_fit, least_squares_from_random_starts
from skinsuction.space import evaluate
from ._objectives import ratio_objective, single_objective, weighted_objective
from skinsuction.space import GriddedSpace
from ._window_focusing import identify_repeated

log = logging.getLogger(__name__)

__all__ = [
    "TARGET",
    "SOURCES",
    "OBJECTIVES",
    "PAPER_TIMING",
    "StudySetup",
    "load_spaces",
    "make_test_curves",
    "read_test_curves",
    "load_setup",
    "build_objective",
    "case_seed",
    "runs_frame",
    "summarise_runs",
    "single_probe_study",
    "alpha_sweep",
    "alpha_threshold",
    "ratio_study",
    "cost_landscape",
    "landscape_summary",
    "timing_study",
    "reference_minimum",
    "optimiser_comparison",
    "fe_in_the_loop",
    "RUN_STUDIES",
    "setup_from_files",
    "write_runs",
    "write_fe_in_the_loop",
    "surrogate_curve",
    "write_surrogate_space",
    "scale_free_setup",
    "compare_spaces",
    "write_space_comparison",
]

#: The paper's test point (section 3.2): X1d, X1h in MPa.
TARGET = (0.0055, 0.00041)

#: Variants of the curve to identify.
SOURCES = {
    "fe": "direct FE run at the test point (honest test)",
    "space": "curve taken from the interpolated space (paper's variant)",
}

#: Objectives by name: probe(s) used and the paper's equation.
OBJECTIVES = {
    "single_6mm": "6 mm probe alone (eq. 4)",
    "single_2mm": "2 mm probe alone (eq. 4)",
    "weighted": "weighted 2 mm + 6 mm (eq. 10)",
    "ratio": "ratio 6 mm / 2 mm (eqs. 11-12)",
}

#: Section 3.3.1: iterations and seconds per identification reported by the paper.
PAPER_TIMING = {"ratio": (10, 1.2), "weighted": (20, 3.8)}

#: Window focusing settings of the paper (section 2.4).
PAPER_WINDOW_FOCUSING = {"n_samples": 1000, "n_best": 20, "tolerance": 1e-6, "max_iter": 200}


# ------------------------------------------------------------------ inputs
def load_spaces(space_path, probes=(2.0, 6.0), bottom="fixed") -> dict:
    """The gridded spaces of ``probes`` from a simulated-space database."""
    from skinsuction.space import read_space

    space = read_space(space_path)
    return {float(p): GriddedSpace.from_space(space, float(p), bottom=bottom) for p in probes}


def make_test_curves(space_path, fe_curve_paths, out_csv=None, *, target=TARGET,
                     bottom="fixed") -> pd.DataFrame:
    """The curves to identify: FE at the test point and the interpolated space there.

    Parameters
    ----------
    space_path : path-like
        Simulated-space database (both probes).
    fe_curve_paths : iterable of path-like
        Curve files (:func:`skinsuction.space.write_curve`) of direct FE runs at
        the test point, one per probe, on the space's mesh and pressures.
    out_csv : path-like, optional
        Where to write the table (atomically).
    target : (float, float)
        The test point (X1d, X1h), MPa.

    Returns
    -------
    DataFrame
        Columns ``source, probe_mm, x1d, x1h, pressure_mbar, deflection_mm``;
        only finite deflections (a non-converged FE curve keeps its converged
        part, with a warning in the log).
    """
    from skinsuction.space import read_curves
    from skinsuction._files import write_table

    frame, _ = read_curves(fe_curve_paths)
    target = np.asarray(target, dtype=float)
    rows = []
    for pid, g in frame.groupby("point_id", sort=False):
        first = g.iloc[0]
        point = np.array([first["x1d"], first["x1h"]], dtype=float)
        if not np.allclose(point, target, rtol=1e-9, atol=0):
            raise ValueError(f"FE curve {pid} is not at the test point {target.tolist()}")
        if not bool(first["converged"]):
            log.warning("FE test curve %s stopped at %s mbar (%s); its converged part is used",
                        pid, first["last_converged_mbar"], first["reason"])
        ok = g[np.isfinite(g["deflection_mm"].to_numpy(float))]
        rows.append(pd.DataFrame({
            "source": "fe", "probe_mm": float(first["probe_mm"]),
            "x1d": target[0], "x1h": target[1],
            "pressure_mbar": ok["pressure_mbar"].to_numpy(float),
            "deflection_mm": ok["deflection_mm"].to_numpy(float),
        }))
    probes = sorted({float(r["probe_mm"].iloc[0]) for r in rows})
    spaces = load_spaces(space_path, probes, bottom)
    for probe in probes:
        s = spaces[probe]
        m = evaluate(s, [target])[0]
        ok = np.isfinite(m)
        if not ok.any():
            raise ValueError(
                f"the {probe:g} mm space cannot be interpolated at the test point "
                f"{target.tolist()} (a node of its stencil did not converge)"
            )
        rows.append(pd.DataFrame({
            "source": "space", "probe_mm": probe, "x1d": target[0], "x1h": target[1],
            "pressure_mbar": s.pressure_mbar[ok], "deflection_mm": m[ok],
        }))
    table = pd.concat(rows, ignore_index=True).sort_values(
        ["source", "probe_mm", "pressure_mbar"], kind="stable").reset_index(drop=True)
    for (source, probe), g in table.groupby(["source", "probe_mm"]):
        log.info("test curve %s %g mm: %d points, M(%g mbar) = %.6f mm", source, probe,
                 len(g), g["pressure_mbar"].iloc[-1], g["deflection_mm"].iloc[-1])
    if out_csv is not None:
        write_table(table, out_csv)
    return table


def read_test_curves(path_or_frame) -> dict:
    """``{source: {probe_mm: (pressure_mbar, deflection_mm)}}`` from the test-curve table."""
    table = path_or_frame if isinstance(path_or_frame, pd.DataFrame) else pd.read_csv(path_or_frame)
    out = {}
    for (source, probe), g in table.groupby(["source", "probe_mm"], sort=True):
        g = g.sort_values("pressure_mbar")
        out.setdefault(str(source), {})[float(probe)] = (
            g["pressure_mbar"].to_numpy(float), g["deflection_mm"].to_numpy(float))
    return out


@dataclass
class StudySetup:
    """Spaces and curves of a study.

    Attributes
    ----------
    spaces : dict
        ``{probe_mm: GriddedSpace}`` for the 2 and 6 mm probes.
    curves : dict
        ``{source: {probe_mm: (pressure_mbar, deflection_mm)}}``.
    target : ndarray (2,)
        The truth (X1d, X1h), MPa.
    window_focusing : dict
        Options of :func:`skinsuction.identify.window_focusing` (N, Nb, C, max_iter).
    """

    spaces: dict
    curves: dict
    target: np.ndarray = field(default_factory=lambda: np.array(TARGET))
    window_focusing: dict = field(default_factory=lambda: dict(PAPER_WINDOW_FOCUSING))

    def __post_init__(self):
        self.target = np.asarray(self.target, dtype=float)

    @property
    def sources(self) -> list:
        return list(self.curves)


def load_setup(space_path, test_curves_path, *, target=TARGET, bottom="fixed",
               window_focusing=None) -> StudySetup:
    """A :class:`StudySetup` from the workflow's files."""
    curves = read_test_curves(test_curves_path)
    probes = sorted({p for c in curves.values() for p in c})
    return StudySetup(
        spaces=load_spaces(space_path, probes, bottom),
        curves=curves,
        target=np.asarray(target, dtype=float),
        window_focusing={**PAPER_WINDOW_FOCUSING, **(window_focusing or {})},
    )


def build_objective(setup: StudySetup, kind: str, source: str, alpha: float = 0.5):
    """The objective ``kind`` (see :data:`OBJECTIVES`) for the curves of ``source``."""
    s, c = setup.spaces, setup.curves[source]
    if kind == "single_6mm":
        return single_objective(s[6.0], c[6.0])
    if kind == "single_2mm":
        return single_objective(s[2.0], c[2.0])
    if kind == "weighted":
        return weighted_objective(s[2.0], c[2.0], s[6.0], c[6.0], alpha=alpha)
    if kind == "ratio":
        return ratio_objective(s[2.0], c[2.0], s[6.0], c[6.0])
    raise ValueError(f"unknown objective {kind!r}; choose among {list(OBJECTIVES)}")


def case_seed(seed: int, *labels) -> np.random.SeedSequence:
    """Independent, reproducible seed of one study case (named by ``labels``).

    >>> a = case_seed(0, "fe", "single_6mm").generate_state(1)
    >>> b = case_seed(0, "fe", "single_2mm").generate_state(1)
    >>> bool(a[0] != b[0])
    True
    """
    key = "/".join(str(x) for x in labels)
    return np.random.SeedSequence([int(seed), zlib.crc32(key.encode())])


# ------------------------------------------------------------------ runs
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


def summarise_runs(runs: pd.DataFrame, target=TARGET, by=("source", "objective"),
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


# ---------------------------------------------------------------- landscape
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


def landscape_summary(landscape: pd.DataFrame, target=TARGET, factor: float = 2.0) -> pd.DataFrame:
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


# ------------------------------------------------------------------ timing
def timing_study(setup: StudySetup, *, repeats=100, seed=0, alpha=0.5, sources=None,
                 objectives=("single_6mm", "single_2mm", "weighted", "ratio")):
    """Iterations and time per identification (median over ``repeats``).

    Each identification is timed on its own: ``seconds`` is the window
    focusing loop (wall), ``cpu_seconds`` its process CPU time; the one-off
    ``setup_seconds`` builds the objective (interpolation of the space to the
    measured pressures).  Returns ``(runs, table)``; the table puts the paper's
    numbers (section 3.3.1) next to ours.
    """
    from ._window_focusing import window_focusing

    frames = []
    for source in sources or setup.sources:
        for kind in objectives:
            t0 = time.perf_counter()
            obj = build_objective(setup, kind, source, alpha)
            setup_s = time.perf_counter() - t0
            window_focusing(obj, seed=0, **setup.window_focusing)  # warm-up (caches, buffers)
            seeds = case_seed(seed, "timing", source, kind).spawn(repeats)
            rows = []
            for k, s in enumerate(seeds):
                c0 = time.process_time()
                r = window_focusing(obj, seed=s, **setup.window_focusing)
                rows.append({"repeat": k, "x1d": r.x1d, "x1h": r.x1h, "E": r.E,
                             "E_unit": r.E_unit, "iterations": r.iterations,
                             "n_evaluations": r.n_evaluations, "seconds": r.seconds,
                             "cpu_seconds": time.process_time() - c0,
                             "converged": r.converged})
            f = pd.DataFrame(rows)
            f.insert(0, "objective", kind)
            f.insert(0, "source", source)
            f["setup_seconds"] = setup_s
            frames.append(f)
    runs = pd.concat(frames, ignore_index=True)
    rows = []
    for (source, kind), g in runs.groupby(["source", "objective"], sort=False):
        paper_it, paper_s = PAPER_TIMING.get(kind, (math.nan, math.nan))
        rows.append({
            "source": source,
            "objective": kind,
            "alpha": alpha if kind == "weighted" else math.nan,
            "runs": len(g),
            "iterations_median": float(g["iterations"].median()),
            "iterations_max": int(g["iterations"].max()),
            "seconds_median": float(g["seconds"].median()),
            "ms_median": 1e3 * float(g["seconds"].median()),
            "cpu_ms_median": 1e3 * float(g["cpu_seconds"].median()),
            "evaluations_median": float(g["n_evaluations"].median()),
            "setup_ms": 1e3 * float(g["setup_seconds"].iloc[0]),
            "converged_fraction": float(g["converged"].mean()),
            "paper_iterations": paper_it,
            "paper_seconds": paper_s,
        })
    return runs, pd.DataFrame(rows)


# ------------------------------------------------------- optimiser comparison
def reference_minimum(objective, points: int = 201):
    """The global minimiser of ``objective`` inside its bounds, found carefully.

    A dense log-spaced grid (``points`` per axis) locates the basins; the 5 best
    grid points are polished by bounded least squares; the lowest end point
    wins.  Returns ``(x (2,), cost)``.
    """
    from scipy import optimize

    lo, hi = np.asarray(objective.lower, float), np.asarray(objective.upper, float)
    axes = [np.geomspace(lo[i], hi[i], points) for i in range(2)]
    for a, l_, h_ in zip(axes, lo, hi):
        a[0], a[-1] = l_, h_
    xd, xh = np.meshgrid(*axes, indexing="ij")
    cand = np.column_stack([xd.ravel(), xh.ravel()])
    j = np.asarray(objective(cand), dtype=float)
    best_x, best_j = None, np.inf
    for k in np.argsort(j)[:5]:
        if not np.isfinite(j[k]):
            break

        def res(x):
            r = objective.residuals(np.asarray(x, float).reshape(1, 2))[0]
            return np.where(np.isfinite(r), r, 1e3)

        sol = optimize.least_squares(res, cand[k], bounds=(lo, hi), x_scale=hi - lo,
                                     method="trf", xtol=1e-15, ftol=1e-15, gtol=1e-15)
        jj = float(objective(sol.x.reshape(1, 2))[0])
        for x, c in ((sol.x, jj), (cand[k], j[k])):
            if c < best_j:
                best_x, best_j = np.array(x, dtype=float), float(c)
    return best_x, best_j


def optimiser_comparison(setup: StudySetup, *, objectives=("single_6mm",), sources=None,
                         runs=100, least_squares_starts=10, de_runs=20, seed=0,
                         alpha=0.5, success_tolerance=0.01, fe_loop=None):
    """Window focusing against scipy optimisers on the same objective and curve.

    Methods (each run with its own seed):

    * ``window_focusing``: the paper's algorithm (N, Nb, C of the setup), ``runs`` runs;
    * ``least_squares_1_start``: ``scipy.optimize.least_squares`` (trf) from one
      random start, ``runs`` runs -- how much a Gauss-Newton-type method depends
      on its start (paper, section 2.3);
    * ``least_squares_{k}_starts``: the best of ``least_squares_starts`` random
      starts, ``runs`` runs;
    * ``differential_evolution``: scipy's, ``de_runs`` runs;
    * ``fe_in_the_loop`` (optional, from :func:`fe_in_the_loop`): least squares
      with the FE model instead of the space, once.

    A run succeeds against the truth if both moduli are within
    ``success_tolerance`` of it, and against the minimum if both are within
    ``success_tolerance`` of the objective's global minimiser
    (:func:`reference_minimum`), which differs from the truth when the curve
    is not in the interpolated space (source ``fe``).

    Returns ``(runs_frame, table)``.
    """
    from ._window_focusing import window_focusing

    rows = []
    ref_rows = {}
    for source in sources or setup.sources:
        for kind in objectives:
            obj = build_objective(setup, kind, source, alpha)
            x_ref, j_ref = reference_minimum(obj)
            ref_rows[(source, kind)] = (x_ref, j_ref, float(obj.error(j_ref)))
            methods = {
                "window_focusing": (runs, lambda s: window_focusing(
                    obj, seed=s, **setup.window_focusing)),
                "least_squares_1_start": (runs, lambda s: least_squares_from_random_starts(
                    obj, seed=s, n_starts=1)),
                f"least_squares_{least_squares_starts}_starts": (
                    runs, lambda s: least_squares_from_random_starts(
                        obj, seed=s, n_starts=least_squares_starts)),
                "differential_evolution": (de_runs, lambda s: differential_evolution_fit(
                    obj, seed=s)),
            }
            for method, (n, fit) in methods.items():
                for k, s in enumerate(case_seed(seed, "compare", source, kind, method).spawn(n)):
                    r = fit(s)
                    rows.append({"source": source, "objective": kind, "method": method,
                                 "run": k, "x1d": float(r.estimate[0]),
                                 "x1h": float(r.estimate[1]), "E": float(r.E),
                                 "n_evaluations": int(r.n_evaluations),
                                 "seconds": float(r.seconds)})
                log.info("%s %s %s: %d runs", source, kind, method, n)
    runs_df = pd.DataFrame(rows)
    table = []
    for (source, kind, method), g in runs_df.groupby(["source", "objective", "method"], sort=False):
        x_ref, j_ref, e_ref = ref_rows[(source, kind)]
        table.append({
            "source": source,
            "objective": kind,
            "method": method,
            "runs": len(g),
            "success_truth": float(np.mean(_success(g["x1d"], g["x1h"], setup.target,
                                                    success_tolerance))),
            "success_minimum": float(np.mean(_success(g["x1d"], g["x1h"], x_ref,
                                                      success_tolerance))),
            "evaluations_median": float(g["n_evaluations"].median()),
            "fe_solves": 0,
            "ms_median": 1e3 * float(g["seconds"].median()),
            "x1d_median": float(g["x1d"].median()),
            "x1h_median": float(g["x1h"].median()),
            "E_median": float(g["E"].median()),
            "x1d_minimum": float(x_ref[0]),
            "x1h_minimum": float(x_ref[1]),
            "E_minimum": e_ref,
        })
    if fe_loop is not None:
        table.append({
            "source": "fe (own mesh)",
            "objective": f"single_{fe_loop['probe_mm']:g}mm",
            "method": "fe_in_the_loop",
            "runs": 1,
            "success_truth": float(fe_loop["success"]),
            "success_minimum": math.nan,
            "evaluations_median": float(fe_loop["fe_solves"]),
            "fe_solves": int(fe_loop["fe_solves"]),
            "ms_median": 1e3 * float(fe_loop["seconds"]),
            "x1d_median": fe_loop["estimate"][0],
            "x1h_median": fe_loop["estimate"][1],
            "E_median": fe_loop["E_um"],
            "x1d_minimum": setup.target[0],
            "x1h_minimum": setup.target[1],
            "E_minimum": 0.0,
        })
    return runs_df, pd.DataFrame(table)


class _Budget(Exception):
    pass


def fe_in_the_loop(*, target=TARGET, bounds, probe_mm=6.0, bottom="fixed", mesh=None,
                   pressures_mbar=None, max_fe_solves=60, seed=0, start=None,
                   diff_step=1e-3, success_tolerance=0.01, simulate=None) -> dict:
    """The standard inverse approach: least squares with the FE model in the loop.

    The curve to identify is a direct FE run at ``target`` with the same mesh
    and pressures as the loop (so the truth is an exact minimum and the run
    measures the optimiser, not the mesh).  ``scipy.optimize.least_squares``
    (trf, bounds, variables scaled by the window, forward differences with a
    relative step ``diff_step``) starts from a seeded random point in ``bounds``
    (or ``start``) and may call the FE model at most ``max_fe_solves`` times
    (Jacobian solves included); at the cap it stops with the best point so far.

    Returns a JSON-able dict: start, estimate, relative errors, success,
    fe_solves, seconds (the loop, without the target solve), seconds per solve,
    E (eq. 7, µm), the settings and the path of the iterates.
    """
    from scipy import optimize

    if simulate is None:
        from skinsuction.model import simulate
    mesh = dict(mesh or {})
    p = np.asarray(pressures_mbar if pressures_mbar is not None else np.arange(0, 101, 10.0),
                   dtype=float)
    lo, hi = (np.asarray(b, dtype=float) for b in bounds)
    target = np.asarray(target, dtype=float)

    t0 = time.perf_counter()
    ref = simulate(target[0], target[1], probe_mm=probe_mm, bottom=bottom,
                   pressures_mbar=p, mesh=mesh)
    target_seconds = time.perf_counter() - t0
    ok = np.isfinite(np.asarray(ref.deflection_mm, dtype=float))
    measured = np.asarray(ref.deflection_mm, dtype=float)

    history, cache = [], {}
    best = {"x": None, "cost": np.inf}

    def residuals(x):
        key = tuple(np.round(x, 15))
        if key in cache:
            return cache[key]
        if len(history) >= max_fe_solves:
            raise _Budget
        s0 = time.perf_counter()
        c = simulate(x[0], x[1], probe_mm=probe_mm, bottom=bottom, pressures_mbar=p, mesh=mesh)
        m = np.asarray(c.deflection_mm, dtype=float)
        r = np.where(np.isfinite(m[ok]), measured[ok] - m[ok], 1.0)  # 1 mm: not converged
        cost = 0.5 * float(r @ r)
        history.append({"x1d": float(x[0]), "x1h": float(x[1]), "cost": cost,
                        "converged": bool(c.converged), "seconds": time.perf_counter() - s0})
        if cost < best["cost"]:
            best.update(x=np.array(x, dtype=float), cost=cost)
        cache[key] = r
        return r

    x0 = (lo + (hi - lo) * np.random.default_rng(seed).random(2)) if start is None \
        else np.asarray(start, dtype=float)
    t0 = time.perf_counter()
    status, message = None, ""
    try:
        sol = optimize.least_squares(residuals, x0, bounds=(lo, hi), x_scale=hi - lo,
                                     method="trf", diff_step=diff_step)
        status, message = int(sol.status), str(sol.message)
        if 0.5 * float(sol.fun @ sol.fun) <= best["cost"]:
            best.update(x=np.array(sol.x, dtype=float), cost=0.5 * float(sol.fun @ sol.fun))
    except _Budget:
        status, message = -100, f"stopped at the cap of {max_fe_solves} FE solves"
    seconds = time.perf_counter() - t0
    x = best["x"]
    rel = x / target - 1
    n_used = int(ok.sum())
    return {
        "method": "scipy.optimize.least_squares (trf, 2-point Jacobian) with the FE model",
        "probe_mm": float(probe_mm),
        "bottom": bottom,
        "mesh": mesh,
        "pressures_mbar": p.tolist(),
        "target": target.tolist(),
        "target_converged": bool(ref.converged),
        "target_seconds": target_seconds,
        "bounds": [lo.tolist(), hi.tolist()],
        "start": np.asarray(x0).tolist(),
        "seed": seed,
        "diff_step": diff_step,
        "max_fe_solves": int(max_fe_solves),
        "estimate": x.tolist(),
        "relative_error": rel.tolist(),
        "success": bool(np.all(np.abs(rel) <= success_tolerance)),
        "success_tolerance": success_tolerance,
        "cost_mm2": best["cost"],
        "E_um": 1e3 * math.sqrt(2 * best["cost"]) / n_used,
        "fe_solves": len(history),
        "seconds": seconds,
        "seconds_per_solve": seconds / max(len(history), 1),
        "status": status,
        "message": message,
        "history": history,
    }


# ------------------------------------------------- file-level entry points
# What the workflow scripts call: paths and the `identification` settings of the
# configuration in, files out.
def setup_from_files(space_path, test_curves_path, settings: dict) -> StudySetup:
    """A :class:`StudySetup` from the workflow's files and ``config["identification"]``."""
    t = settings.get("target") or {"x1d": TARGET[0], "x1h": TARGET[1]}
    return load_setup(space_path, test_curves_path, target=(t["x1d"], t["x1h"]),
                      bottom=settings.get("bottom", "fixed"),
                      window_focusing=settings.get("window_focusing"))


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


def scale_free_setup(space_dir, test_curves_path, *, target=TARGET, bottom="fixed",
                     window_focusing=None, sources=("fe",)) -> StudySetup:
    """A :class:`StudySetup` on the scale-free space (its neo-Hookean rays).

    Only the ``sources`` of the test curves are kept: the curve taken from the
    paper grid's interpolant is not a test of another space.
    """
    from skinsuction.space import NeoHookeanSlice, read_ray_spaces

    base = read_ray_spaces(space_dir)["neo_hookean"]
    if base.spec.bottom != bottom:
        raise ValueError(f"{space_dir}: the scale-free space has bottom {base.spec.bottom!r}, "
                         f"not {bottom!r}")
    curves = {k: v for k, v in read_test_curves(test_curves_path).items() if k in sources}
    return StudySetup(spaces={p: NeoHookeanSlice(base, p) for p in base.probes_mm},
                      curves=curves, target=np.asarray(target, dtype=float),
                      window_focusing={**PAPER_WINDOW_FOCUSING, **(window_focusing or {})})


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
    from ._polish import polish

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


def write_fe_in_the_loop(space_path, out_json, settings: dict, loop: dict,
                         pressures_mbar, simulate=None) -> dict:
    """Run :func:`fe_in_the_loop` within the bounds of the space; write the JSON record."""
    import json

    from skinsuction._files import atomic_output

    probe = float(loop.get("probe_mm", 6.0))
    bottom = settings.get("bottom", "fixed")
    s = load_spaces(space_path, (probe,), bottom)[probe]
    t = settings.get("target") or {"x1d": TARGET[0], "x1h": TARGET[1]}
    result = fe_in_the_loop(
        target=(t["x1d"], t["x1h"]), bounds=(s.lower, s.upper), probe_mm=probe, bottom=bottom,
        mesh=loop.get("mesh"), pressures_mbar=pressures_mbar,
        max_fe_solves=int(loop.get("max_fe_solves", 80)), seed=int(loop.get("seed", 0)),
        success_tolerance=float(settings.get("success_tolerance", 0.01)), simulate=simulate,
    )
    log.info("FE in the loop: %d FE solves, %.1f s, estimate %s (relative error %s), %s",
             result["fe_solves"], result["seconds"], result["estimate"],
             result["relative_error"], result["message"])
    with atomic_output(out_json) as tmp:
        tmp.write_text(json.dumps(result, indent=2) + "\n", encoding="utf-8")
    return result


def surrogate_curve(x1d, x1h, x2d=0.0, x2h=0.0, t_d=1.0, t_h=1.0, probe_mm=6.0,
                    bottom="fixed", pressures_mbar=None, mesh=None):
    """The analytic surrogate as a :class:`skinsuction.model.Curve`-like object.

    Same call as :func:`skinsuction.model.simulate`, no FE: for tests,
    examples and plumbing runs of the workflow only.
    """
    from types import SimpleNamespace

    from ._surrogate import surrogate_deflection

    p = np.arange(0.0, 101.0, 2.0) if pressures_mbar is None else np.asarray(pressures_mbar, float)
    m = surrogate_deflection(x1d, x1h, p, probe_mm)
    return SimpleNamespace(pressure_mbar=p, deflection_mm=m, converged=True,
                           last_converged_mbar=float(p[-1]), reason="", newton_iterations=0,
                           dofs=0, seconds=0.0, info={"surrogate": True, "mesh": mesh})


def write_surrogate_space(path, x1d, x1h, pressures_mbar, probes=(2.0, 6.0), *,
                          curves_dir=None, name="surrogate") -> None:
    """A simulated-space database filled with the analytic surrogate (not the FE model).

    For tests and demonstrations of the identification without FE runs.  With
    ``curves_dir`` the per-point curve files are written there as well (as the
    workflow's ``results/curves``).
    """
    import tempfile
    from pathlib import Path

    from skinsuction.space import assemble_space, grid_points, point_id, write_curve

    spec = {"probes_mm": list(probes), "x1d": list(x1d), "x1h": list(x1h)}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(curves_dir) if curves_dir is not None else Path(tmp)
        paths = []
        for params in grid_points(spec):
            c = surrogate_curve(**params, pressures_mbar=pressures_mbar)
            paths.append(write_curve(c, params, folder / f"{point_id(params)}.parquet",
                                     {"surrogate": True}))
        assemble_space(paths, path, config={"spaces": {name: spec}, "surrogate": True},
                       name=name)
