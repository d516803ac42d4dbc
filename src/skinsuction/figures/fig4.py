"""Figure 4: 100 single-probe identifications with the 6 mm and with the 2 mm probe.

Paper section 3.2: the test curve X1d = 0.0055 MPa, X1h = 0.00041 MPa is
identified 100 times (N = 1000, Nb = 20, C = 1e-6 µm) with the 6 mm probe alone
(a) and the 2 mm probe alone (b).  The paper took the curve from the
interpolated space; we show that variant (hollow markers) next to the honest
one, a direct FE run at the test point (filled markers).  Rows: identified X1d
and X1h against the identification number; the truth is the dashed line.
"""

from __future__ import annotations

import pandas as pd

from skinsuction.figures import _style

#: Probe objectives in panel order: (a) 6 mm, (b) 2 mm.
PANELS = (("single_6mm", "6 mm"), ("single_2mm", "2 mm"))

#: Look of the two test-curve variants.
SOURCE_STYLE = {
    "fe": {"color": "#1b6ca8", "marker": "o", "markerfacecolor": "#1b6ca8",
           "label": "test curve: direct FE run"},
    "space": {"color": "#d1495b", "marker": "s", "markerfacecolor": "none",
              "label": "test curve: interpolated space (paper)"},
}



def _fmt_pct(x):
    return f"{x:+.1f} %" if abs(x) < 999.5 else f"{x:+.3g} %"


def plot_fig4(runs: pd.DataFrame, table: pd.DataFrame, target):
    """Figure 4 from the runs and their table (:func:`table_fig4`)."""
    import matplotlib.pyplot as plt

    sources = [s for s in SOURCE_STYLE if s in set(runs["source"])]
    with _style.style():
        fig, axes = plt.subplots(2, 2, figsize=(_style.WIDTH_IN, 4.8), sharex=True)
        for col, (kind, label) in enumerate(PANELS):
            for row, (name, sym, unit_scale) in enumerate(
                    (("x1d", "X_1^d", 1.0), ("x1h", "X_1^h", 1e3))):
                ax = axes[row, col]
                for source in sources:
                    g = runs[(runs["source"] == source) & (runs["objective"] == kind)]
                    st = SOURCE_STYLE[source]
                    ax.plot(g["repeat"] + 1, g[name] * unit_scale, linestyle="none",
                            marker=st["marker"], markersize=3.2, color=st["color"],
                            markerfacecolor=st["markerfacecolor"], label=st["label"])
                lines = []
                for source in sources:
                    t = table[(table["source"] == source) & (table["objective"] == kind)]
                    if len(t):
                        t = t.iloc[0]
                        lines.append(f"{'FE' if source == 'fe' else 'space'}: mean error "
                                     f"{_fmt_pct(t[f'{name}_error_mean_pct'])}, "
                                     f"max {t[f'{name}_error_max_pct']:.3g} %")
                if lines:
                    ax.text(0.98, 0.96, "\n".join(lines), transform=ax.transAxes, ha="right",
                            va="top", fontsize=6.5, zorder=5,
                            bbox={"boxstyle": "round,pad=0.25", "facecolor": "white",
                                  "edgecolor": "0.7", "alpha": 0.85})
                truth = target[row] * unit_scale
                ax.axhline(truth, color="0.2", linestyle="--", linewidth=0.9, label="truth")
                ax.set_ylabel(f"identified ${sym}$ ({'MPa' if row == 0 else 'kPa'})")
                if row == 0:
                    ax.set_title(f"({chr(ord('a') + col)}) {label} probe")
                else:
                    ax.set_xlabel("identification")
        handles, labels = axes[0, 0].get_legend_handles_labels()
        fig.legend(handles, labels, loc="lower center", ncol=len(labels), frameon=False)
        fig.tight_layout(rect=(0, 0.06, 1, 1))
    return fig


