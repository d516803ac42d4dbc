"""Precision against design: one panel per parameter (``skinsuction design``).

Each design a column: the median relative half-width of the 95 % interval over the
skins (marker) and its upper quantile (bar end); an open interval (an end at the
space's edge) is drawn at the top of the panel; the question's target, if any, a
dashed line; the recommended design is named in the title.
"""

from __future__ import annotations

import numpy as np

from ._style import WIDTH_IN, panel_label, plt, save, style

__all__ = ["plot_design_precision"]

PARAMETERS = ("X1d", "X1h")
#: mode 1 and mode 2 designs' spectrum (a ramp's is not predicted: no marker)
SPECTRUM = ("g_1", "tau_1")


def plot_design_precision(summary, question, path):
    """Draw the design table's precision per parameter and save it to ``path``.

    Parameters
    ----------
    summary : pandas.DataFrame
        :func:`skinsuction.design.summarize`.
    question : skinsuction.design.Question
    path : path-like

    Returns
    -------
    path
    """
    names = list(summary["design"])
    x = np.arange(len(names))
    params = PARAMETERS + tuple(p for p in SPECTRUM if f"{p}_median" in summary)
    with style():
        fig, axes = plt.subplots(1, len(params), figsize=(WIDTH_IN, 0.45 * WIDTH_IN),
                                 sharey=True, squeeze=False)
        axes = axes[0]
        for k, (ax, p) in enumerate(zip(axes, params)):
            med = 100 * summary[f"{p}_median"].to_numpy(float)
            top = 100 * summary[f"{p}_quantile"].to_numpy(float)
            finite = np.concatenate([med[np.isfinite(med)], top[np.isfinite(top)]])
            cap = 2 * max(finite.max(initial=10.0), 10.0)
            med_d, top_d = np.minimum(med, cap), np.minimum(top, cap)
            ax.vlines(x, med_d, top_d, color="#4a6fa5", lw=2)
            ax.plot(x, med_d, "o", color="#4a6fa5", label="median")
            ax.plot(x, top_d, "_", ms=12, color="#4a6fa5",
                    label=f"{100 * question.quantile:g}th percentile")
            open_ = np.isinf(top)
            ax.plot(x[open_], np.full(open_.sum(), cap), "^", color="#d1495b",
                    label="open (space edge)")
            if p in question.precision:
                ax.axhline(100 * question.precision[p], ls="--", color="0.3", lw=1,
                           label="target")
            ax.set_yscale("log")
            ax.set_xticks(x, names, rotation=60, ha="right", fontsize=7)
            ax.set_ylabel("95 % interval half-width (%)" if k == 0 else "")
            ax.set_title(p)
            panel_label(ax, f"({chr(97 + k)})")
        axes[0].legend(fontsize=7, loc="lower left")
        fig.tight_layout()
        save(fig, path)
        plt.close(fig)
    return path
