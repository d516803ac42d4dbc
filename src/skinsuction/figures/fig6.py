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
"""

from __future__ import annotations


import pandas as pd

from skinsuction.figures import _style

__all__ = ["plot_fig6"]

PROBE_COLOR = {6.0: "#1b6ca8", 2.0: "#d1495b"}
SYMBOL = {"X1d": ("$X_1^d$", "MPa"), "X1h": ("$X_1^h$", "MPa"), "X2d": ("$X_2^d$", "MPa"),
          "t_d": ("$t_d$", "mm"), "lambda0": (r"$\lambda_0$", "")}


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


