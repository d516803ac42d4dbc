"""Where each cause is detectable: the draws of the wide-domain confusion benchmark.

One panel per cause: X1d across, the hidden effect up (X2d/X1d, t_d, lambda0),
each draw a marker: detectable and named right, detectable and named wrong where
another cause could be told apart, detectable but mimicked by another cause (its
noise-free curves leave a BIC gap below the tie rule's: no diagnosis can do more
than report the tie), beyond the simulated space, or not detectable (the
neo-Hookean model absorbs it below the noise); the marker size grows with X1h/X1d.
"""

from __future__ import annotations

import numpy as np

from ._style import WIDTH_IN, panel_label, plt, save, style

__all__ = ["plot_detectability"]

_KINDS = {
    "right": ("detectable, named right", "#2e933c", "o"),
    "wrong": ("detectable, named wrong", "#d1495b", "X"),
    "mimicked": ("mimicked by another cause", "#7b5ea7", "D"),
    "beyond": ("beyond the simulated space", "#f2a541", "s"),
    "hidden": ("not detectable", "#9a9a9a", "."),
}

_LABELS = {"strain_stiffening": ("X2d / X1d", "log"), "dermis_thickness": ("t_d (mm)", "linear"),
           "pre_tension": ("lambda0", "linear")}


def _kind(row):
    if row["verdict"] == "beyond_space":
        return "beyond"
    if not row["detectable"]:
        return "hidden"
    if row["named"] == row["truth"]:
        return "right"
    # False (or numpy's False) only: a row without the rival fits (NaN) counts as wrong
    return "mimicked" if row.get("distinguishable", True) == 0 else "wrong"


def plot_detectability(rows, *paths):
    """Draw the rows of ``benchmarks/diagnose_confusion.py`` (one per draw)."""
    rows = rows[~rows["named"].isin(("fe_failed", "input_rejected"))
                & (rows["truth"] != "none")].copy()
    causes = list(dict.fromkeys(rows["truth"]))
    with style():
        fig, axes = plt.subplots(1, max(1, len(causes)), squeeze=False,
                                 figsize=(WIDTH_IN, 2.6), constrained_layout=True)
        for k, cause in enumerate(causes):
            ax = axes[0, k]
            g = rows[rows["truth"] == cause]
            kinds = g.apply(_kind, axis=1)
            for key, (label, colour, marker) in _KINDS.items():
                sel = g[kinds == key]
                if sel.empty:
                    continue
                size = 12 + 40 * (np.log10(sel["ratio"]) + 2.6) / 1.6
                ax.scatter(sel["x1d"], sel["coordinate"], s=size, c=colour, marker=marker,
                           label=label, alpha=0.85, edgecolors="none")
            ax.set_xscale("log")
            name, scale = _LABELS.get(cause, (cause, "linear"))
            ax.set_yscale(scale)
            ax.set_xlabel("X1d (MPa)")
            ax.set_ylabel(name)
            frac = float(g["detectable"].astype(bool).mean()) if len(g) else float("nan")
            ax.set_title(f"{cause}: {100 * frac:.0f} % detectable", fontsize=8)
            panel_label(ax, f"({'abc'[k % 3]})")
        handles, labels = axes[0, 0].get_legend_handles_labels()
        for ax in axes[0, 1:]:
            for h, lab in zip(*ax.get_legend_handles_labels()):
                if lab not in labels:
                    handles.append(h)
                    labels.append(lab)
        fig.legend(handles, labels, loc="outside lower center", ncol=3, fontsize=7)
        save(fig, *paths)
    return fig
