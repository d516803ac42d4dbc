"""Figure 7: identified moduli against the weight alpha of the 2 mm cost (eq. 10).

Paper section 3.3.1: 100 identifications of the weighted objective per alpha
(alpha = 0: 6 mm alone; alpha = 1: 2 mm alone) for the test curve X1d = 0.0055
MPa, X1h = 0.00041 MPa.  The paper: above alpha = 0.75 the results drift;
alpha = 0.5 identifies in every case.  Dots: every identification (shifted
sideways per test-curve variant); lines: medians; dashed: the truth.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from skinsuction.figures import _style
from skinsuction.figures.fig4 import SOURCE_STYLE


def plot_fig7(runs: pd.DataFrame, table: pd.DataFrame, target):
    """Figure 7 from the runs and their table."""
    import matplotlib.pyplot as plt

    sources = [s for s in SOURCE_STYLE if s in set(runs["source"])]
    alphas = np.unique(runs["alpha"].to_numpy(float))
    step = np.min(np.diff(alphas)) if alphas.size > 1 else 0.1
    with _style.style():
        fig, axes = plt.subplots(1, 2, figsize=(_style.WIDTH_IN, 3.2), sharex=True)
        for ax, (name, sym, scale, unit) in zip(
                axes, (("x1d", "X_1^d", 1.0, "MPa"), ("x1h", "X_1^h", 1e3, "kPa"))):
            for k, source in enumerate(sources):
                st = SOURCE_STYLE[source]
                g = runs[runs["source"] == source]
                shift = (k - (len(sources) - 1) / 2) * 0.18 * step
                ax.plot(g["alpha"] + shift, g[name] * scale, linestyle="none",
                        marker=st["marker"], markersize=2.2, alpha=0.35, color=st["color"],
                        markerfacecolor=st["markerfacecolor"])
                t = table[table["source"] == source].sort_values("alpha")
                ax.plot(t["alpha"] + shift, t[f"{name}_median"] * scale, color=st["color"],
                        marker=st["marker"], markerfacecolor=st["markerfacecolor"],
                        markersize=4, label=st["label"] + " (median)")
            ax.axhline(target[0 if name == "x1d" else 1] * scale, color="0.2", linestyle="--",
                       linewidth=0.9, label="truth")
            ax.set_xlabel(r"weight $\alpha$ of the 2 mm cost")
            ax.set_ylabel(f"identified ${sym}$ ({unit})")
            ax.set_title(f"({'a' if name == 'x1d' else 'b'}) ${sym}$")
        handles, labels = axes[0].get_legend_handles_labels()
        fig.legend(handles, labels, loc="lower center", ncol=len(labels), frameon=False)
        fig.tight_layout(rect=(0, 0.08, 1, 1))
    return fig


