"""Figure 7: identified moduli against the weight alpha of the 2 mm cost (eq. 10).

Paper section 3.3.1: 100 identifications of the weighted objective per alpha
(alpha = 0: 6 mm alone; alpha = 1: 2 mm alone) for the test curve X1d = 0.0055
MPa, X1h = 0.00041 MPa.  The paper: above alpha = 0.75 the results drift;
alpha = 0.5 identifies in every case.  Dots: every identification (shifted
sideways per test-curve variant); lines: medians; dashed: the truth.

Examples
--------
>>> import pandas as pd
>>> runs = pd.DataFrame({"source": "fe", "objective": "weighted", "alpha": [0.0, 0.0, 1.0, 1.0],
...                      "repeat": [0, 1, 0, 1], "x1d": [0.0055, 0.0055, 0.0056, 0.0054],
...                      "x1h": [0.00041, 0.00041, 0.0007, 0.0001], "E": 0.1, "E_unit": "µm",
...                      "iterations": 12, "seconds": 0.01, "n_evaluations": 12000,
...                      "converged": True})
>>> table, threshold = table_fig7(runs)
>>> table["success_fraction"].tolist(), threshold["last_alpha_ok_from_0"].tolist()
([1.0, 0.0], [0.0])
>>> len(plot_fig7(runs, table).axes)
2
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from skinsuction.figures import _style
from skinsuction.figures.fig4 import SOURCE_STYLE, TARGET


def table_fig7(runs: pd.DataFrame, target=TARGET, success_tolerance=0.01, min_success=0.95):
    """Per test curve and alpha: estimates, errors, success; and the alpha threshold."""
    from skinsuction.identify.study import alpha_threshold, summarise_runs

    table = summarise_runs(runs, target, ("source", "alpha"), success_tolerance)
    return table, alpha_threshold(table, min_success)


def plot_fig7(runs: pd.DataFrame, table: pd.DataFrame, target=TARGET):
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


def build_fig7(runs_csv, png, pdf, csv, threshold_csv, target=TARGET, success_tolerance=0.01):
    """Read the runs; write the table, the alpha threshold (CSV) and the figure."""
    import matplotlib.pyplot as plt

    from skinsuction._files import write_table

    runs = pd.read_csv(runs_csv)
    table, threshold = table_fig7(runs, target, success_tolerance)
    write_table(table, csv)
    write_table(threshold, threshold_csv)
    fig = plot_fig7(runs, table, target)
    _style.save(fig, png, pdf)
    plt.close(fig)
    return table
