"""Tables of the identification study: timing and optimiser comparison (CSV + Markdown).

Examples
--------
>>> import pandas as pd
>>> print(markdown_table(pd.DataFrame({"a": [1.0, 2.5], "b": ["x", "y"]})))
| a | b |
|---:|:---|
| 1 | x |
| 2.5 | y |
"""

from __future__ import annotations

import math

import pandas as pd

from skinsuction._files import atomic_output, write_table


def _cell(x, digits: int = 4) -> str:
    if isinstance(x, float):
        if math.isnan(x):
            return ""
        return f"{x:.{digits}g}"
    return str(x)


def markdown_table(frame: pd.DataFrame, digits: int = 4) -> str:
    """A GitHub Markdown table; numbers right-aligned, ``digits`` significant digits."""
    cols = list(frame.columns)
    num = [pd.api.types.is_numeric_dtype(frame[c]) for c in cols]
    lines = ["| " + " | ".join(cols) + " |",
             "|" + "|".join("---:" if n else ":---" for n in num) + "|"]
    for _, row in frame.iterrows():
        lines.append("| " + " | ".join(_cell(row[c], digits) for c in cols) + " |")
    return "\n".join(lines)


def write_markdown(path, title: str, sections) -> None:
    """Write ``# title`` then each ``(text, frame)`` section (frame may be None)."""
    parts = [f"# {title}", ""]
    for text, frame in sections:
        if text:
            parts += [text, ""]
        if frame is not None:
            parts += [markdown_table(frame), ""]
    with atomic_output(path) as tmp:
        tmp.write_text("\n".join(parts), encoding="utf-8")


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

    import numpy as np

    from skinsuction.identify.study import setup_from_files, timing_study

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

    from skinsuction.identify.study import optimiser_comparison, setup_from_files

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
