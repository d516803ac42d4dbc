"""The paper's figures and tables as files: compute from the study's results, then draw.

Each ``build_*`` is what one workflow rule runs (rule -> thin script -> one
function here): it reads the rule's inputs, computes the table, writes it as
CSV and draws the figure with :mod:`skinsuction.figures` (which draws from
plain tables only).  The test point ``target`` (X1d, X1h) comes from the
configuration (``identification.target``).

Examples
--------
Figure 4b from a toy landscape (log E over X1d, X1h):

>>> import numpy as np, pandas as pd
>>> xd, xh = np.meshgrid(np.geomspace(1e-3, 1e-1, 5), np.geomspace(1e-5, 2e-3, 5), indexing="ij")
>>> e = (np.log(xd / 0.0055) ** 2 + 0.01 * np.log(xh / 4.1e-4) ** 2).ravel() + 1e-3
>>> land = pd.DataFrame({"objective": "single_2mm", "x1d": xd.ravel(), "x1h": xh.ravel(),
...                      "cost": e, "E": e, "E_unit": "µm"})
>>> fig = plot_fig4b(land, landscape_summary(land, (0.0055, 4.1e-4)), (0.0055, 4.1e-4))
>>> fig.axes[0].get_title()
'(a) 2 mm probe alone'
"""

from __future__ import annotations

import json

import numpy as np
import pandas as pd

from skinsuction._files import atomic_output, write_table
from skinsuction.figures import save_figure
from skinsuction.figures.fig4 import PANELS, plot_fig4
from skinsuction.figures.fig4b import VALLEY_FACTOR, plot_fig4b
from skinsuction.figures.fig5 import plot_fig5, table_fig5
from skinsuction.figures.fig6 import plot_fig6
from skinsuction.figures.fig7 import plot_fig7
from skinsuction.figures.fig8 import plot_fig8
from skinsuction.figures.tables import write_markdown
from skinsuction.identify import correlation_error
from skinsuction.identify.measured_fit import identify_measured
from skinsuction.measured import load_measured

from ._runs import alpha_threshold, cost_landscape, landscape_summary, summarise_runs
from ._setup import build_objective, setup_from_files
from ._timing import optimiser_comparison, timing_study


def _e_um(residual_um) -> float:
    """Eq. 7 on a residual vector (µm)."""
    return float(correlation_error(np.asarray(residual_um, dtype=float)))


# ---------------------------------------------------------------- fig4
def table_fig4(runs: pd.DataFrame, target, success_tolerance=0.01) -> pd.DataFrame:
    """Per test curve and probe: estimates, errors in % of the truth, success rate.

    Examples
    --------
    >>> import numpy as np, pandas as pd
    >>> runs = pd.DataFrame({"source": "fe", "objective": ["single_6mm"] * 3 + ["single_2mm"] * 3,
    ...                      "repeat": [0, 1, 2] * 2, "x1d": 0.0055, "x1h": 0.00041,
    ...                      "E": 0.1, "E_unit": "µm", "iterations": 12, "seconds": 0.01,
    ...                      "n_evaluations": 12000, "converged": True})
    >>> table = table_fig4(runs, target=(0.0055, 0.00041))
    >>> table[["objective", "success_fraction"]].values.tolist()
    [['single_6mm', 1.0], ['single_2mm', 1.0]]
    >>> len(plot_fig4(runs, table, (0.0055, 0.00041)).axes)
    4
    """

    table = summarise_runs(runs, target, ("source", "objective"), success_tolerance)
    order = {k: i for i, (k, _) in enumerate(PANELS)}
    table["_o"] = table["objective"].map(order)
    table["_s"] = table["source"].map({"fe": 0, "space": 1})
    return table.sort_values(["_s", "_o"]).drop(columns=["_o", "_s"]).reset_index(drop=True)


def build_fig4(runs_csv, png, pdf, csv, target, success_tolerance=0.01) -> pd.DataFrame:
    """Read the runs, write the table (CSV) and the figure (PNG, PDF)."""
    import matplotlib.pyplot as plt

    runs = pd.read_csv(runs_csv)
    table = table_fig4(runs, target, success_tolerance)
    write_table(table, csv)
    fig = plot_fig4(runs, table, target)
    save_figure(fig, png, pdf)
    plt.close(fig)
    return table


# ---------------------------------------------------------------- fig4b
def build_fig4b(space_path, test_curves_path, png, pdf, csv, landscape_out, settings: dict,
                points: int = 161, source: str = "fe") -> pd.DataFrame:
    """Compute the landscapes, write them (Parquet), the summary (CSV) and the figure."""
    import matplotlib.pyplot as plt

    setup = setup_from_files(space_path, test_curves_path, settings)
    alpha = float(settings.get("alpha", 0.5))
    land = cost_landscape(setup, source=source, points=points, alpha=alpha)
    with atomic_output(landscape_out) as tmp:
        land.to_parquet(tmp, index=False)
    summary = landscape_summary(land, setup.target, VALLEY_FACTOR)
    summary.insert(0, "source", source)
    write_table(summary, csv)
    fig = plot_fig4b(land, summary, setup.target, alpha)
    save_figure(fig, png, pdf)
    plt.close(fig)
    return summary


# ---------------------------------------------------------------- fig5
def identify_runs(measured_csv, space_parquet, probe_mm=6.0, repeats=100, seed=0,
                  window_focusing=None):
    """100 single-probe identifications (``skinsuction identify``) -> (runs, result)."""

    result = identify_measured(measured_csv, space_parquet, objective="single",
                               probe_mm=probe_mm, repeats=repeats, seed=seed,
                               window_focusing=window_focusing)
    runs = pd.DataFrame(result["runs"]).rename(
        columns={"x1d_mpa": "x1d_mpa", "x1h_mpa": "x1h_mpa", "E": "E_um"})
    runs.insert(0, "repeat", np.arange(len(runs)))
    return runs, result


def _truth_from_header(measured_csv):

    meta = load_measured(measured_csv).metadata
    try:
        return {"x1d": float(meta["true_x1d_mpa"]), "x1h": float(meta["true_x1h_mpa"]),
                "cause": meta.get("true_cause", "")}
    except (KeyError, ValueError):
        return None


def build_fig5(measured_csv, space_parquet, png, pdf, csv, runs_csv=None, probe_mm=6.0,
               repeats=100, seed=0, window_focusing=None) -> pd.DataFrame:
    """Identify, write the table (and runs) as CSV and the figure as PNG and PDF."""
    import matplotlib.pyplot as plt

    runs, result = identify_runs(measured_csv, space_parquet, probe_mm, repeats, seed,
                                 window_focusing)
    truth = _truth_from_header(measured_csv)
    table = table_fig5(runs, truth, result)
    write_table(table, csv)
    if runs_csv:
        write_table(runs, runs_csv)
    fig = plot_fig5(runs, table, truth, probe_mm)
    save_figure(fig, png, pdf)
    plt.close(fig)
    return table


# ---------------------------------------------------------------- fig6
def table_fig6(check: pd.DataFrame) -> pd.DataFrame:
    """Per panel: model, parameters, E of the FE curves and of the interpolated fit (µm).

    Examples
    --------
    >>> import pandas as pd
    >>> t = pd.DataFrame({"panel": ["a"] * 2 + ["b"] * 2, "label": ["nh"] * 2 + ["ext"] * 2,
    ...                   "model": ["neo_hookean"] * 2 + ["c"] * 2, "probe_mm": 6.0,
    ...                   "pressure_mbar": [50.0, 100.0] * 2, "measured_mm": [0.5, 0.8] * 2,
    ...                   "fe_mm": [0.51, 0.79, 0.5, 0.8], "interpolated_mm": [0.51, 0.79, 0.5, 0.8],
    ...                   "converged": True, "param_X1d": 0.05, "param_X1h": 5e-4})
    >>> s = table_fig6(t)
    >>> s["E_fe_um"].round(2).tolist()
    [7.07, 0.0]
    >>> len(plot_fig6(t, s).axes)
    4
    """

    rows = []
    for panel, g in check.groupby("panel", sort=True):
        row = {"panel": panel, "label": g["label"].iloc[0], "model": g["model"].iloc[0]}
        for c in g.columns:
            if c.startswith("param_") and g[c].notna().any():
                row[c[6:]] = float(g[c].iloc[0])
        res_fe = 1e3 * (g["measured_mm"] - g["fe_mm"]).to_numpy(float)
        res_in = 1e3 * (g["measured_mm"] - g["interpolated_mm"]).to_numpy(float)
        row["E_fe_um"] = _e_um(res_fe)
        row["E_interpolated_um"] = _e_um(res_in)
        row["max_abs_fe_minus_interpolated_um"] = float(
            np.nanmax(np.abs(1e3 * (g["fe_mm"] - g["interpolated_mm"]))))
        row["converged"] = bool(g["converged"].all())
        for probe, gp in g.groupby("probe_mm"):
            r = 1e3 * (gp["measured_mm"] - gp["fe_mm"]).to_numpy(float)
            row[f"E_fe_{probe:g}mm_um"] = _e_um(r)
        rows.append(row)
    return pd.DataFrame(rows)


def build_fig6(report_json, check_csv, png, pdf, csv):
    """Read the diagnosis report and FE check, write the table and the figure."""
    import matplotlib.pyplot as plt

    report = json.loads(open(report_json, encoding="utf-8").read())
    check = pd.read_csv(check_csv)
    table = table_fig6(check)
    table.insert(1, "cause", report["cause"])
    write_table(table, csv)
    fig = plot_fig6(check, table, title=f"{report['input'].get('file')}: diagnosis "
                                        f"'{report['cause']}'")
    save_figure(fig, png, pdf)
    plt.close(fig)
    return table


# ---------------------------------------------------------------- fig7
def table_fig7(runs: pd.DataFrame, target, success_tolerance=0.01, min_success=0.95):
    """Per test curve and alpha: estimates, errors, success; and the alpha threshold.

    Examples
    --------
    >>> import pandas as pd
    >>> runs = pd.DataFrame({"source": "fe", "objective": "weighted", "alpha": [0.0, 0.0, 1.0, 1.0],
    ...                      "repeat": [0, 1, 0, 1], "x1d": [0.0055, 0.0055, 0.0056, 0.0054],
    ...                      "x1h": [0.00041, 0.00041, 0.0007, 0.0001], "E": 0.1, "E_unit": "µm",
    ...                      "iterations": 12, "seconds": 0.01, "n_evaluations": 12000,
    ...                      "converged": True})
    >>> table, threshold = table_fig7(runs, target=(0.0055, 0.00041))
    >>> table["success_fraction"].tolist(), threshold["last_alpha_ok_from_0"].tolist()
    ([1.0, 0.0], [0.0])
    >>> len(plot_fig7(runs, table, (0.0055, 0.00041)).axes)
    2
    """

    table = summarise_runs(runs, target, ("source", "alpha"), success_tolerance)
    return table, alpha_threshold(table, min_success)


def build_fig7(runs_csv, png, pdf, csv, threshold_csv, target, success_tolerance=0.01):
    """Read the runs; write the table, the alpha threshold (CSV) and the figure."""
    import matplotlib.pyplot as plt

    runs = pd.read_csv(runs_csv)
    table, threshold = table_fig7(runs, target, success_tolerance)
    write_table(table, csv)
    write_table(threshold, threshold_csv)
    fig = plot_fig7(runs, table, target)
    save_figure(fig, png, pdf)
    plt.close(fig)
    return table


# ---------------------------------------------------------------- fig8
def curves_fig8(setup, runs: pd.DataFrame) -> pd.DataFrame:
    """Long table of the curves of panels (a) and (b), per test-curve variant.

    Columns ``source, kind, pressure_mbar, value`` with kinds ``M_6mm``,
    ``M_2mm`` (mm), ``Gamma``, ``Theta_truth``, ``Theta_estimate``.
    """

    rows = []
    for source in setup.sources:
        for probe in (6.0, 2.0):
            p, m = setup.curves[source][probe]
            rows.append(pd.DataFrame({"source": source, "kind": f"M_{probe:g}mm",
                                      "pressure_mbar": p, "value": m}))
        obj = build_objective(setup, "ratio", source)
        est = runs.loc[runs["source"] == source, ["x1d", "x1h"]].median().to_numpy(float)
        theta = obj.theta(np.array([setup.target, est]))
        for kind, values in (("Gamma", obj.gamma), ("Theta_truth", theta[0]),
                             ("Theta_estimate", theta[1])):
            rows.append(pd.DataFrame({"source": source, "kind": kind,
                                      "pressure_mbar": obj.pressure_mbar, "value": values}))
    return pd.concat(rows, ignore_index=True)


def build_fig8(space_path, test_curves_path, runs_csv, png, pdf, csv, curves_csv,
               settings: dict) -> pd.DataFrame:
    """Read the ratio runs; write the summary and curve tables (CSV) and the figure."""
    import matplotlib.pyplot as plt

    setup = setup_from_files(space_path, test_curves_path, settings)
    runs = pd.read_csv(runs_csv)
    table = summarise_runs(runs, setup.target, ("source", "objective"),
                           float(settings.get("success_tolerance", 0.01)))
    write_table(table, csv)
    curves = curves_fig8(setup, runs)
    write_table(curves, curves_csv)
    fig = plot_fig8(curves, runs, setup.target)
    save_figure(fig, png, pdf)
    plt.close(fig)
    return table


# ---------------------------------------------------------------- tables
# ------------------------------------------------------------------ timing
TIMING_COLUMNS = {
    "objective": "objective",
    "source": "test curve",
    "iterations_median": "iterations (median)",
    "ms_median": "ms per identification (median, wall)",
    "cpu_ms_median": "CPU ms (median)",
    "setup_ms": "setup ms (once)",
    "evaluations_median": "candidates evaluated",
    "paper_iterations": "paper: iterations",
    "paper_seconds": "paper: s",
}


def build_timing(space_path, test_curves_path, csv, markdown, runs_csv, settings: dict):
    """Time the identifications (median over ``repeats``); write CSV, Markdown, runs."""
    import platform



    setup = setup_from_files(space_path, test_curves_path, settings)
    alpha = float(settings.get("alpha", 0.5))
    runs, table = timing_study(setup, repeats=int(settings.get("repeats", 100)),
                               seed=int(settings.get("seed", 0)), alpha=alpha)
    write_table(runs, runs_csv)
    write_table(table, csv)
    wf = setup.window_focusing
    shown = table.copy()
    shown["objective"] = [f"weighted (α = {alpha:g})" if k == "weighted" else k
                          for k in shown["objective"]]
    shown = shown[list(TIMING_COLUMNS)].rename(columns=TIMING_COLUMNS)
    write_markdown(markdown, "Time per identification", [
        (f"Window focusing with N = {wf['n_samples']}, Nb = {wf['n_best']}, "
         f"C = {wf['tolerance']:g} (unit of E), median over {len(runs) // len(table)} runs "
         "per row, each timed on its own (wall clock of the iterations; setup = "
         "interpolating the space to the measured pressures, once per curve). "
         f"Machine: {platform.machine()}, Python {platform.python_version()}, "
         f"NumPy {np.__version__}, one thread. The paper's numbers (section 3.3.1, "
         "MATLAB, 2010 hardware) are for its ratio and weighted identifications.", shown),
    ])
    return table


# ------------------------------------------------------ optimiser comparison
COMPARISON_COLUMNS = {
    "source": "test curve",
    "objective": "objective",
    "method": "method",
    "runs": "runs",
    "success_truth": "success (truth ±1 %)",
    "success_minimum": "success (minimum ±1 %)",
    "evaluations_median": "evaluations (median)",
    "fe_solves": "FE solves",
    "ms_median": "ms per run (median)",
    "x1d_median": "X1d median (MPa)",
    "x1h_median": "X1h median (MPa)",
}


def build_comparison(space_path, test_curves_path, fe_loop_json, csv, markdown, runs_csv,
                     settings: dict):
    """Compare window focusing with scipy optimisers; write CSV, Markdown and runs."""
    import json

    setup = setup_from_files(space_path, test_curves_path, settings)
    cmp = settings.get("comparison") or {}
    tol = float(settings.get("success_tolerance", 0.01))
    fe_loop = json.loads(open(fe_loop_json, encoding="utf-8").read()) if fe_loop_json else None
    runs, table = optimiser_comparison(
        setup, objectives=tuple(cmp.get("objectives", ("single_6mm",))),
        runs=int(cmp.get("runs", 100)),
        least_squares_starts=int(cmp.get("least_squares_starts", 10)),
        de_runs=int(cmp.get("differential_evolution_runs", 20)),
        seed=int(settings.get("seed", 0)), alpha=float(settings.get("alpha", 0.5)),
        success_tolerance=tol, fe_loop=fe_loop,
    )
    write_table(runs, runs_csv)
    write_table(table, csv)
    shown = table[list(COMPARISON_COLUMNS)].rename(columns=COMPARISON_COLUMNS)
    shown = shown.rename(columns=lambda c: c.replace("1 %", f"{100 * tol:g} %"))
    notes = [
        ("Same simulated space and test curves for every method on the space. "
         "'success (truth)': both moduli within the tolerance of the test point; "
         "'success (minimum)': within the tolerance of the objective's global minimiser "
         "(dense grid + polishing), which is not the truth when the curve is not in the "
         "interpolated space (test curve 'fe'). Evaluations: candidates (curves "
         "interpolated from the space) or FE solves.", shown),
    ]
    if fe_loop is not None:
        mesh = fe_loop.get("mesh")
        notes.append((
            f"FE in the loop: scipy least_squares (trf, forward-difference Jacobian, relative "
            f"step {fe_loop['diff_step']:g}) with the FE model ({fe_loop['probe_mm']:g} mm "
            f"probe, mesh {mesh}, {len(fe_loop['pressures_mbar'])} pressures) from the random "
            f"start {[round(x, 6) for x in fe_loop['start']]}, capped at "
            f"{fe_loop['max_fe_solves']} FE solves: {fe_loop['fe_solves']} solves in "
            f"{fe_loop['seconds']:.1f} s ({fe_loop['seconds_per_solve']:.2f} s each), "
            f"estimate {[float(f'{x:.5g}') for x in fe_loop['estimate']]}, relative error "
            f"{[f'{100 * x:+.2f} %' for x in fe_loop['relative_error']]}; {fe_loop['message']}. "
            "Its test curve is an FE run on the same coarse mesh and pressures, so the truth "
            "is an exact minimum.", None))
    write_markdown(markdown, "Optimisers on the simulated space", notes)
    return table
