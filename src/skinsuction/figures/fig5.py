"""Figure 5: 100 identifications of a "measured" curve with the 6 mm probe (neo-Hookean).

Paper section 3.2: the experimental 6 mm curve is identified 100 times on the
simulated space (window focusing, N = 1000, Nb = 20, C = 1e-6 µm); the scatter
of the estimates comes from the misfit of the neo-Hookean model and the
sampling of the space.  Here the "measured" curve is the shipped synthetic
example (``data/example_suction_synthetic.csv``, labelled as synthetic), the
space is the paper's grid (eq. 3) and the identification is exactly
``skinsuction identify --objective single --probe 6``.  Top: X1d, bottom: X1h
against the identification number, with their mean; the true moduli of the
synthetic curve (from its header) are shown dashed, for honesty about what a
neo-Hookean identification of a stiffening skin returns.

Examples
--------
>>> import pandas as pd
>>> runs = pd.DataFrame({"repeat": [0, 1, 2], "x1d_mpa": [0.05, 0.051, 0.049],
...                      "x1h_mpa": [5e-4, 5.2e-4, 4.9e-4], "E_um": [3.0, 3.1, 2.9],
...                      "iterations": [12, 13, 12]})
>>> t = table_fig5(runs, truth={"x1d": 0.05, "x1h": 5e-4})
>>> round(float(t["x1d_mean_mpa"].iloc[0]), 3), len(plot_fig5(runs, t).axes)
(0.05, 2)
"""

from __future__ import annotations

import pandas as pd

from skinsuction.figures import _style

__all__ = ["table_fig5", "plot_fig5"]


def table_fig5(runs: pd.DataFrame, truth=None, result=None) -> pd.DataFrame:
    """Mean, sd, min and max of the identified moduli (MPa) and E (µm)."""
    row = {"runs": len(runs)}
    for name in ("x1d", "x1h"):
        x = runs[f"{name}_mpa"].to_numpy(float)
        row[f"{name}_mean_mpa"] = float(x.mean())
        row[f"{name}_sd_mpa"] = float(x.std(ddof=1)) if len(x) > 1 else 0.0
        row[f"{name}_min_mpa"] = float(x.min())
        row[f"{name}_max_mpa"] = float(x.max())
        row[f"{name}_relative_spread"] = row[f"{name}_sd_mpa"] / abs(row[f"{name}_mean_mpa"])
        if truth:
            row[f"{name}_true_mpa"] = truth[name]
            row[f"{name}_mean_error_pct"] = 100 * (row[f"{name}_mean_mpa"] / truth[name] - 1)
    row["E_mean_um"] = float(runs["E_um"].mean())
    row["E_min_um"] = float(runs["E_um"].min())
    row["E_max_um"] = float(runs["E_um"].max())
    row["iterations_median"] = float(runs["iterations"].median())
    if truth and truth.get("cause"):
        row["true_cause"] = truth["cause"]
    if result is not None:
        row["space_sha256"] = result["space"]["sha256"]
        row["input_sha256"] = result["input"]["sha256"]
    return pd.DataFrame([row])


def plot_fig5(runs: pd.DataFrame, table: pd.DataFrame, truth=None, probe_mm=6.0):
    """Figure 5 from the runs and their table."""
    import matplotlib.pyplot as plt

    t = table.iloc[0]
    with _style.style():
        fig, axes = plt.subplots(2, 1, figsize=(_style.WIDTH_IN * 0.62, 4.4), sharex=True)
        for ax, name, sym, scale, unit in ((axes[0], "x1d", "X_1^d", 1.0, "MPa"),
                                           (axes[1], "x1h", "X_1^h", 1e3, "kPa")):
            ax.plot(runs["repeat"] + 1, runs[f"{name}_mpa"] * scale, linestyle="none",
                    marker="o", markersize=3, color="#1b6ca8", label="identification")
            ax.axhline(t[f"{name}_mean_mpa"] * scale, color="#1b6ca8", linewidth=1.0,
                       label=f"mean {t[f'{name}_mean_mpa'] * scale:.3g} {unit}")
            if truth:
                ax.axhline(truth[name] * scale, color="0.2", linestyle="--", linewidth=0.9,
                           label=f"true value of the synthetic curve {truth[name] * scale:.3g} {unit}")
            ax.set_ylabel(f"identified ${sym}$ ({unit})")
            ax.legend(loc="best", fontsize=6.5, framealpha=0.85, edgecolor="0.8")
        axes[1].set_xlabel("identification")
        axes[0].set_title(f"{len(runs)} neo-Hookean identifications, {probe_mm:g} mm probe, "
                          f"E = {t['E_min_um']:.3g}-{t['E_max_um']:.3g} µm", fontsize=8)
        fig.tight_layout()
    return fig


