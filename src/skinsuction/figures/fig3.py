"""Figure 3: maximal deflection vs hypodermis modulus for three interface conditions.

Paper section 3.1: apex deflection M at the maximal pressure (100 mbar) as a
function of the hypodermis modulus X1h, for the hypodermis/bone interface
restrained laterally and axially (``fixed``), axially only (``axial``) or
suppressed (``free``); dermis modulus X1d = 80 kPa, both layers 1 mm thick;
panel (a) 6 mm aperture, panel (b) 2 mm aperture.

Points whose solve stopped before the maximal pressure are drawn hollow, at the
deflection of their last converged pressure (a lower bound of M at 100 mbar).

Examples
--------
>>> import pandas as pd
>>> table = pd.DataFrame({
...     "probe_mm": [6.0, 6.0], "bottom": ["fixed", "fixed"], "x1d": [0.08, 0.08],
...     "x1h": [1e-4, 1e-3], "pressure_mbar": [100.0, 100.0],
...     "deflection_mm": [1.2, 0.9], "reached": [True, True],
...     "last_converged_mbar": [100.0, 100.0], "deflection_last_mm": [1.2, 0.9]})
>>> fig = plot_fig3(table)
>>> [ax.get_title() for ax in fig.axes]
['(a) 6 mm aperture, $X_1^d$ = 0.08 MPa']
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from skinsuction.figures import _style

#: Columns of the Figure 3 table.
TABLE_COLUMNS = (
    "probe_mm",
    "bottom",
    "x1d",
    "x1h",
    "x2d",
    "x2h",
    "t_d",
    "t_h",
    "pressure_mbar",
    "deflection_mm",
    "reached",
    "converged",
    "last_converged_mbar",
    "deflection_last_mm",
    "reason",
    "point_id",
)


def table_fig3(frame: pd.DataFrame, pressure_mbar: float | None = None) -> pd.DataFrame:
    """The numbers behind Figure 3, one row per grid point.

    Parameters
    ----------
    frame : DataFrame
        Long-format curves (columns of :data:`skinsuction.space.COLUMNS`), e.g.
        from :func:`skinsuction.space.read_curves`.
    pressure_mbar : float, optional
        Pressure at which M is read; default the largest pressure of each curve.

    Returns
    -------
    DataFrame
        Columns :data:`TABLE_COLUMNS`. ``deflection_mm`` is M at
        ``pressure_mbar`` (NaN if not reached); ``reached`` tells whether the
        solver got there; ``deflection_last_mm`` is M at ``last_converged_mbar``.
    """
    rows = []
    for pid, g in frame.groupby("point_id", sort=False):
        g = g.sort_values("pressure_mbar")
        first = g.iloc[0]
        p = g["pressure_mbar"].to_numpy(float)
        m = g["deflection_mm"].to_numpy(float)
        target = float(p.max()) if pressure_mbar is None else float(pressure_mbar)
        at = np.isclose(p, target, rtol=0, atol=1e-9)
        if not at.any():
            raise ValueError(f"point {pid} has no pressure {target} mbar")
        converged = bool(first["converged"])
        last = float(first["last_converged_mbar"])
        reached = converged or (np.isfinite(last) and last >= target - 1e-9)
        finite = np.isfinite(m)
        rows.append(
            {
                **{k: first[k] for k in ("probe_mm", "bottom", "x1d", "x1h", "x2d", "x2h", "t_d", "t_h")},
                "pressure_mbar": target,
                "deflection_mm": float(m[at][0]) if reached else np.nan,
                "reached": bool(reached and np.isfinite(m[at][0])),
                "converged": converged,
                "last_converged_mbar": last,
                "deflection_last_mm": float(m[finite][-1]) if finite.any() else np.nan,
                "reason": first["reason"],
                "point_id": pid,
            }
        )
    table = pd.DataFrame(rows, columns=list(TABLE_COLUMNS))
    return table.sort_values(["probe_mm", "bottom", "x1h"], ascending=[False, True, True]).reset_index(
        drop=True
    )


def plot_fig3(table: pd.DataFrame, xlim=(1e-5, 1e-1)):
    """Figure 3 from its table (see :func:`table_fig3`).

    One panel per aperture, largest first ((a) 6 mm, (b) 2 mm), M at the maximal
    pressure vs X1h on a log axis, one line per interface condition. Points that
    did not reach the maximal pressure are hollow markers at their last converged
    deflection, explained in the legend.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    probes = sorted(table["probe_mm"].unique(), reverse=True)
    bottoms = [b for b in _style.BOTTOM_STYLE if b in set(table["bottom"])]
    pressure = table["pressure_mbar"].max()
    with _style.style():
        fig, axes = plt.subplots(
            1,
            len(probes),
            figsize=(max(_style.WIDTH_IN * 0.5 * len(probes), 5.0), 3.2),
            squeeze=False,
            sharey=False,
        )
        axes = axes[0]
        hollow_all, empty_all = 0, 0
        for n, (ax, probe) in enumerate(zip(axes, probes)):
            sub = table[table["probe_mm"] == probe]
            hollow_total, empty_total = 0, 0
            for bottom in bottoms:
                st = _style.BOTTOM_STYLE[bottom]
                g = sub[sub["bottom"] == bottom].sort_values("x1h")
                ok = g[g["reached"].astype(bool)]
                ax.plot(
                    ok["x1h"],
                    ok["deflection_mm"],
                    color=st["color"],
                    marker=st["marker"],
                    linestyle=st["linestyle"],
                    label=st["label"],
                    clip_on=False,  # markers at the ends of the X1h range stay whole
                )
                bad = g[~g["reached"].astype(bool)]
                shown = bad[np.isfinite(bad["deflection_last_mm"].astype(float))]
                hollow_total += len(shown)
                empty_total += len(bad) - len(shown)
                if len(shown):
                    ax.plot(
                        shown["x1h"],
                        shown["deflection_last_mm"],
                        linestyle="none",
                        marker=st["marker"],
                        markerfacecolor="none",
                        markeredgecolor=st["color"],
                        markersize=7,
                        clip_on=False,
                    )
            ax.set_xscale("log")
            # the paper's range; widened only for data outside it
            lo, hi = xlim
            if len(sub) and sub["x1h"].min() < lo:
                lo = sub["x1h"].min() / 1.5
            if len(sub) and sub["x1h"].max() > hi:
                hi = sub["x1h"].max() * 1.5
            ax.set_xlim(lo, hi)
            ax.set_xlabel(r"hypodermis modulus $X_1^h$ (MPa)")
            ax.set_ylabel(f"deflection M at {pressure:g} mbar (mm)")
            x1d = sub["x1d"].unique()
            x1d_txt = f", $X_1^d$ = {x1d[0]:g} MPa" if len(x1d) == 1 else ""
            ax.set_title(f"({chr(ord('a') + n)}) {probe:g} mm aperture{x1d_txt}")
            hollow_all += hollow_total
            empty_all += empty_total
        handles, labels = axes[0].get_legend_handles_labels()
        fig.legend(handles, labels, loc="lower center", ncol=len(labels), frameon=False,
                   bbox_to_anchor=(0.5, 0.0))
        bottom_margin = 0.11
        if hollow_all or empty_all:
            text = (
                f"not converged up to {pressure:g} mbar ({hollow_all} point(s)): "
                "M at the last converged pressure, a lower bound"
            )
            if empty_all:
                text += f"; {empty_all} point(s) without any converged increment not shown"
            hollow = Line2D([], [], linestyle="none", marker="o", markerfacecolor="none",
                            markeredgecolor="0.3", markersize=7)
            fig.legend([hollow], [text], loc="lower center", frameon=False,
                       bbox_to_anchor=(0.5, 0.065))
            bottom_margin = 0.17
        fig.tight_layout(rect=(0, bottom_margin, 1, 1))
    return fig


def build_fig3(curve_paths, png, pdf, csv, pressure_mbar=None, points=None) -> pd.DataFrame:
    """Read the Figure 3 curves, write the table (CSV) and the figure (PNG, PDF).

    ``points``: the figure's point ids, when the files hold others too.
    """
    import matplotlib.pyplot as plt

    from skinsuction.space import read_curves
    from skinsuction._files import write_table

    frame, _ = read_curves(curve_paths, points)
    table = table_fig3(frame, pressure_mbar)
    write_table(table, csv)
    fig = plot_fig3(table)
    _style.save(fig, png, pdf)
    plt.close(fig)
    return table
