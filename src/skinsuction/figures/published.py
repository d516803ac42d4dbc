"""The published Cutometer values of the face against the skins that reach them.

Two panels: the R5-R7 plane and the R0-R2 plane, the published ranges as a box,
the FE mode-1 skins of creep alone (grey) and of creep with a stiffening dermis
(blue), each model's nearest skin to the box as a star and its lowest R5 with R0,
R2 and R7 published as a diamond
(:func:`skinsuction.evaluation.published_ranges_study`).
"""

from __future__ import annotations

from matplotlib.patches import Rectangle

from ._style import WIDTH_IN, panel_label, plt, save, style

__all__ = ["plot_published_ranges"]

#: Colour of each model.
COLOURS = {"creep": "0.55", "creep+stiffening": "tab:blue"}


def plot_published_ranges(frame, box: dict, *paths):
    """Draw the benchmark's rows and the published box.

    Parameters
    ----------
    frame : pandas.DataFrame
        Rows of :func:`skinsuction.evaluation.published_ranges_study`.
    box : dict
        ``{"R0": (low, high), ...}`` (:data:`skinsuction.evaluation.PUBLISHED_FACE`).
    *paths : path-like
        Where to save the figure.

    Returns
    -------
    matplotlib.figure.Figure
    """
    with style():
        fig, axes = plt.subplots(1, 2, figsize=(WIDTH_IN, 0.45 * WIDTH_IN),
                                 constrained_layout=True)
        for ax, (x, y), letter in zip(axes, (("R5", "R7"), ("R0", "R2")), "ab"):
            (x0, x1), (y0, y1) = box[x], box[y]
            ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, lw=1.2,
                                   ec="tab:red", label="published (face)"))
            for model, colour in COLOURS.items():
                sel = frame[(frame["model"] == model) & (frame["stage"] == "draw")]
                ax.scatter(sel[x], sel[y], s=6, color=colour, alpha=0.6, lw=0,
                           label=f"{model} ({len(sel)} FE skins)")
                g = frame[frame["model"] == model]
                if len(g):
                    best = g.loc[g["distance"].idxmin()]
                    ax.scatter([best[x]], [best[y]], marker="*", s=70, color=colour,
                               edgecolor="k", lw=0.5, zorder=5)
                # the lowest R5 with R0, R2 and R7 published: how far down each model reaches
                ok = g.copy()
                for k in ("R0", "R2", "R7"):
                    lo, hi = box[k]
                    ok = ok[(ok[k] >= lo) & (ok[k] <= hi)]
                if len(ok):
                    low = ok.loc[ok["R5"].idxmin()]
                    ax.scatter([low[x]], [low[y]], marker="D", s=28, color=colour,
                               edgecolor="k", lw=0.5, zorder=5)
            ax.set_xlabel(x + (" (mm)" if x == "R0" else ""))
            ax.set_ylabel(y)
            panel_label(ax, f"({letter})")
        axes[0].legend(fontsize=6, loc="lower right")
        save(fig, *paths)
    return fig
