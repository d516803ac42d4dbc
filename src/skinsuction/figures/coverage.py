"""The coverage frontier of the scale-free space: how far each FE ray was loaded.

One panel per (probe, model): the rays' X1h/X1d across, the cause's value up,
coloured by the highest load p/X1d each ray reached (white: the whole range).
A ray that stopped early bounds the space there: a curve needs X1d at least
``p_max / load_reached`` at that (X1h/X1d, cause value).
"""

from __future__ import annotations

import numpy as np

from ._style import WIDTH_IN, panel_label, plt, save, style

__all__ = ["plot_coverage"]


def _grid(frame):
    ratios = np.sort(frame["ratio"].unique())
    coords = np.sort(frame["coordinate"].fillna(0.0).unique())
    z = np.full((coords.size, ratios.size), np.nan)
    for _, row in frame.iterrows():
        i = np.searchsorted(coords, 0.0 if np.isnan(row["coordinate"]) else row["coordinate"])
        j = np.searchsorted(ratios, row["ratio"])
        z[i, j] = row["load_reached"]
    return ratios, coords, z


def plot_coverage(frontier, *paths):
    """Draw the frontier table of :func:`skinsuction.diagnose.coverage_frontier`.

    ``frontier`` holds the rows of every model (``model`` column); the figure is
    saved to each of ``paths`` and returned.
    """
    models = list(dict.fromkeys(frontier["model"]))
    probes = sorted(frontier["probe_mm"].unique())
    load_max = float(frontier["load_max"].max())
    with style():
        fig, axes = plt.subplots(len(probes), len(models), squeeze=False,
                                 figsize=(WIDTH_IN * max(1.0, len(models) / 4),
                                          1.9 * len(probes) + 0.6),
                                 constrained_layout=True)
        cmap = plt.get_cmap("viridis").copy()
        cmap.set_over("white")
        image = None
        letters = iter("abcdefghijklmnopqrstuvwxyz")
        for r, probe in enumerate(probes):
            for c, model in enumerate(models):
                ax = axes[r, c]
                sel = frontier[(frontier["model"] == model) & (frontier["probe_mm"] == probe)]
                ratios, coords, z = _grid(sel)
                shown = np.where(z >= load_max * (1 - 1e-9), np.inf, z)
                image = ax.imshow(shown, origin="lower", aspect="auto", cmap=cmap,
                                  vmin=0, vmax=load_max * (1 - 1e-6),
                                  extent=(-0.5, ratios.size - 0.5, -0.5, coords.size - 0.5))
                ax.grid(False)
                step = max(1, ratios.size // 4)
                ax.set_xticks(range(0, ratios.size, step))
                ax.set_xticklabels([f"{x:.0e}" for x in ratios[::step]], rotation=30)
                if model == "neo_hookean":
                    ax.set_yticks([])
                else:
                    ax.set_yticks(range(coords.size))
                    ax.set_yticklabels([f"{x:g}" for x in coords])
                n_short = int((z < load_max * (1 - 1e-9)).sum())
                ax.set_title(f"{probe:g} mm, {model.replace('_', ' ')}\n{n_short} of {z.size} rays short",
                             fontsize=7)
                if r == len(probes) - 1:
                    ax.set_xlabel("X1h / X1d")
                panel_label(ax, f"({next(letters)})")
        fig.colorbar(image, ax=axes, extend="max", shrink=0.8,
                     label=f"highest p/X1d reached (mbar/MPa); white: all {load_max:g}")
        save(fig, *paths)
    return fig
