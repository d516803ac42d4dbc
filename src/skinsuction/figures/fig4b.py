"""Figure 4b (beyond the paper): the cost landscapes log10 E(X1d, X1h).

E (eq. 7) of the test curve for the 2 mm and 6 mm single-probe objectives, the
weighted objective (eq. 10) and the ratio objective (eqs. 11-12), on log axes
over the simulated space.  Thin white lines: iso-E every 0.25 decade; the
orange contour encloses the valley ``E <= 2 E_min``; the star is the truth, the
cross the grid minimum.  A valley that runs along X1h means the objective cannot tell the
hypodermis modulus: that is what the 2 mm probe shows (paper, section 3.2).
Grey: the space is not usable there (non-converged FE points).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from skinsuction.figures import _style

TITLES = {
    "single_2mm": "2 mm probe alone",
    "single_6mm": "6 mm probe alone",
    "weighted": "weighted, α = {alpha:g}",
    "ratio": "ratio 6 mm / 2 mm",
}


#: The valley of a landscape: E <= VALLEY_FACTOR * min E.
VALLEY_FACTOR = 2.0


def plot_fig4b(landscape: pd.DataFrame, summary: pd.DataFrame, target, alpha=0.5):
    """Figure 4b from the landscape (:func:`skinsuction.paper.cost_landscape`)."""
    import matplotlib.pyplot as plt
    from matplotlib import colors

    kinds = [k for k in TITLES if k in set(landscape["objective"])]
    ncol = 2 if len(kinds) > 1 else 1
    nrow = int(np.ceil(len(kinds) / ncol))
    with _style.style():
        fig, axes = plt.subplots(nrow, ncol, figsize=(_style.WIDTH_IN, 2.9 * nrow + 0.3),
                                 squeeze=False, sharex=True, sharey=True)
        for n, (ax, kind) in enumerate(zip(axes.flat, kinds)):
            g = landscape[landscape["objective"] == kind]
            xd = np.unique(g["x1d"].to_numpy(float))
            xh = np.unique(g["x1h"].to_numpy(float))
            e = np.full((xd.size, xh.size), np.nan)
            i = np.searchsorted(xd, g["x1d"].to_numpy(float))
            j = np.searchsorted(xh, g["x1h"].to_numpy(float))
            e[i, j] = g["E"].to_numpy(float)
            finite = np.isfinite(e) & (e > 0)
            loge = np.where(finite, np.log10(np.where(finite, e, 1.0)), np.nan)
            ax.set_facecolor("0.75")
            mesh = ax.pcolormesh(xd, xh, loge.T, shading="nearest", cmap="viridis",
                                 norm=colors.Normalize(np.nanmin(loge), np.nanmax(loge)),
                                 rasterized=True)
            s = summary[summary["objective"] == kind].iloc[0]
            lo, hi = np.nanmin(loge), np.nanmax(loge)
            if hi > lo:  # iso-lines every 0.25 decade show the shape of the valleys
                ax.contour(xd, xh, loge.T, levels=np.arange(np.ceil(4 * lo) / 4, hi, 0.25),
                           colors="white", linewidths=0.35, alpha=0.6, linestyles="solid")
            if np.isfinite(s["valley_level"]) and s["valley_level"] > 0:
                ax.contour(xd, xh, loge.T, levels=[np.log10(s["valley_level"])],
                           colors="#ffb000", linewidths=1.3, linestyles="solid")
            ax.plot(*target, marker="*", color="#ff4040", markersize=11,
                    markeredgecolor="white", linestyle="none", label="truth")
            ax.plot(s["x1d_at_minimum"], s["x1h_at_minimum"], marker="X", color="white",
                    markeredgecolor="black", markersize=7, linestyle="none",
                    label="grid minimum")
            ax.set_xscale("log")
            ax.set_yscale("log")
            unit = s["E_unit"]
            cb = fig.colorbar(mesh, ax=ax, pad=0.02)
            cb.set_label("log$_{10}$ E" + ("" if unit == "1" else f" (E in {unit})"))
            ax.set_title(f"({chr(ord('a') + n)}) " + TITLES[kind].format(alpha=alpha))
            ax.grid(False)
        for ax in axes[-1]:
            ax.set_xlabel(r"dermis $X_1^d$ (MPa)")
        for ax in axes[:, 0]:
            ax.set_ylabel(r"hypodermis $X_1^h$ (MPa)")
        for ax in list(axes.flat)[len(kinds):]:
            ax.set_visible(False)
        from matplotlib.lines import Line2D

        handles, labels = axes[0, 0].get_legend_handles_labels()
        handles.append(Line2D([], [], color="#ffb000", linewidth=1.3))
        labels.append(f"valley: E ≤ {VALLEY_FACTOR:g} × minimum")
        fig.legend(handles, labels, loc="lower center", ncol=3, frameon=False)
        fig.tight_layout(rect=(0, 0.05, 1, 1))
    return fig


