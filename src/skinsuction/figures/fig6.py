"""Figure 6: measured against simulated curves, (a) neo-Hookean, (b) the extended model.

Paper section 3.2: the neo-Hookean fit of the experimental curve leaves a high
correlation error (a); the extended potential of eq. 9 fits it clearly better
(b).  Here the "measured" curves are the shipped synthetic example, the
models are those of its diagnosis (``results/diagnosis/example/report.json``):
(a) the neo-Hookean fit, (b) the cause the diagnosis chose (or its best
candidate, labelled "not retained", when the verdict is ``none``).  The lines
are direct FE runs at the identified parameters (``fe_check.csv``), so the E
printed per panel (eq. 7, both probes' points together) is that of true
simulated curves; the E of the interpolated fit is given next to it.

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

from __future__ import annotations

import json

import numpy as np
import pandas as pd

from skinsuction.figures import _style

__all__ = ["table_fig6", "plot_fig6", "build_fig6"]

PROBE_COLOR = {6.0: "#1b6ca8", 2.0: "#d1495b"}
SYMBOL = {"X1d": ("$X_1^d$", "MPa"), "X1h": ("$X_1^h$", "MPa"), "X2d": ("$X_2^d$", "MPa"),
          "t_d": ("$t_d$", "mm"), "lambda0": (r"$\lambda_0$", "")}


def table_fig6(check: pd.DataFrame) -> pd.DataFrame:
    """Per panel: model, parameters, E of the FE curves and of the interpolated fit (µm)."""
    from skinsuction.diagnose._check import e_um

    rows = []
    for panel, g in check.groupby("panel", sort=True):
        row = {"panel": panel, "label": g["label"].iloc[0], "model": g["model"].iloc[0]}
        for c in g.columns:
            if c.startswith("param_") and g[c].notna().any():
                row[c[6:]] = float(g[c].iloc[0])
        res_fe = 1e3 * (g["measured_mm"] - g["fe_mm"]).to_numpy(float)
        res_in = 1e3 * (g["measured_mm"] - g["interpolated_mm"]).to_numpy(float)
        row["E_fe_um"] = e_um(res_fe)
        row["E_interpolated_um"] = e_um(res_in)
        row["max_abs_fe_minus_interpolated_um"] = float(
            np.nanmax(np.abs(1e3 * (g["fe_mm"] - g["interpolated_mm"]))))
        row["converged"] = bool(g["converged"].all())
        for probe, gp in g.groupby("probe_mm"):
            r = 1e3 * (gp["measured_mm"] - gp["fe_mm"]).to_numpy(float)
            row[f"E_fe_{probe:g}mm_um"] = e_um(r)
        rows.append(row)
    return pd.DataFrame(rows)


def _params_text(row):
    out = []
    for k, (sym, unit) in SYMBOL.items():
        if k in row and pd.notna(row[k]):
            out.append(f"{sym} = {row[k]:.3g}{' ' + unit if unit else ''}")
    return ", ".join(out)


def plot_fig6(check: pd.DataFrame, table: pd.DataFrame, title=None):
    """Figure 6 from the FE check and its table: curves on top, residuals below."""
    import matplotlib.pyplot as plt

    panels = list(table["panel"])
    with _style.style():
        fig, axes = plt.subplots(2, len(panels), figsize=(_style.WIDTH_IN, 4.6),
                                 sharex=True, sharey="row", squeeze=False,
                                 gridspec_kw={"height_ratios": [2.2, 1]})
        for col, (_, row) in enumerate(table.iterrows()):
            top, bottom = axes[0, col], axes[1, col]
            g = check[check["panel"] == row["panel"]]
            for probe, gp in sorted(g.groupby("probe_mm"), key=lambda kv: -kv[0]):
                color = PROBE_COLOR.get(probe, "0.3")
                top.plot(gp["pressure_mbar"], gp["measured_mm"], linestyle="none", marker="o",
                         markersize=2.6, markerfacecolor="none", color=color,
                         label=f"{probe:g} mm measured (synthetic)")
                top.plot(gp["pressure_mbar"], gp["fe_mm"], color=color,
                         label=f"{probe:g} mm simulated (FE)")
                bottom.plot(gp["pressure_mbar"], 1e3 * (gp["measured_mm"] - gp["fe_mm"]),
                            marker="o", markersize=2.2, linewidth=0.8, color=color,
                            label=f"{probe:g} mm")
            bottom.axhline(0.0, color="0.3", linewidth=0.8)
            top.set_title(f"({row['panel']}) {row['label']}\n{_params_text(row)}\n"
                          f"E = {row['E_fe_um']:.3g} µm (interpolated fit "
                          f"{row['E_interpolated_um']:.3g} µm)", fontsize=7)
            bottom.set_xlabel("suction pressure p (mbar)")
        axes[0, 0].set_ylabel("apex deflection M (mm)")
        axes[1, 0].set_ylabel("measured − sim. (µm)")
        fig.align_ylabels(axes[:, 0])
        axes[0, 0].legend(loc="upper left", frameon=False, fontsize=6.5)
        if title:
            fig.suptitle(title, fontsize=8)
        fig.tight_layout()
    return fig


def build_fig6(report_json, check_csv, png, pdf, csv):
    """Read the diagnosis report and FE check, write the table and the figure."""
    import matplotlib.pyplot as plt

    from skinsuction._files import write_table

    report = json.loads(open(report_json, encoding="utf-8").read())
    check = pd.read_csv(check_csv)
    table = table_fig6(check)
    table.insert(1, "cause", report["cause"])
    write_table(table, csv)
    fig = plot_fig6(check, table, title=f"{report['input'].get('file')}: diagnosis "
                                        f"'{report['cause']}'")
    _style.save(fig, png, pdf)
    plt.close(fig)
    return table
