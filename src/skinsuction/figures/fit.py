"""Measured against fitted curves, with residuals (``skinsuction identify``).

Examples
--------
>>> result = {"fit": {"6": {"pressure_mbar": [0, 50, 100], "measured_mm": [0, 0.5, 0.8],
...                         "fitted_mm": [0, 0.49, 0.81], "residual_um": [0, 10, -10],
...                         "curve": ""}},
...           "estimate": {"x1d_mpa": 0.03, "x1h_mpa": 4e-4},
...           "settings": {"objective": "single", "alpha": None},
...           "E": {"at_estimate": 1.0, "unit": "µm"}, "input": {"path": "m.csv"}}
>>> fig = plot_fit(result)
>>> [ax.get_ylabel() for ax in fig.axes]
['deflection M (mm)', 'residual (µm)']
"""

from __future__ import annotations

import numpy as np

from skinsuction.figures import _style

#: Colour per probe diameter (mm, as text).
PROBE_COLOR = {"6": "#1b6ca8", "2": "#d1495b"}
#: Box behind text over curves (legible wherever the curves run).
TEXT_BOX = {"boxstyle": "round,pad=0.3", "facecolor": "white", "alpha": 0.85,
            "edgecolor": "0.8"}


def _arr(values):
    return np.array([np.nan if v is None else v for v in values], dtype=float)


def interval_lines(intervals: dict, names, units=None) -> str:
    """Text lines ``X1d in [lo, hi] MPa`` of profile-likelihood intervals (figure text)."""
    units = units or {}
    lines = [f"{100 * intervals['level']:g} % intervals (profile likelihood)"]
    for name in names:
        iv = intervals.get(name)
        if not iv:
            continue
        lo = ("≤" if iv["lower_open"] else "") + f"{iv['lower']:.3g}"
        hi = ("≥" if iv["upper_open"] else "") + f"{iv['upper']:.3g}"
        lines.append(f"{name} ∈ [{lo}, {hi}] {units.get(name, 'MPa')}".rstrip())
    return "\n".join(lines)


def plot_fit(result: dict):
    """Figure of :func:`skinsuction.identify.measured_fit.identify_measured`'s result.

    Top: measured deflections (markers) and the space at the estimate (lines)
    against pressure, one colour per probe.  Bottom: residuals (measured -
    fitted) in µm.
    """
    import matplotlib.pyplot as plt

    est = result["estimate"]
    settings = result["settings"]
    with _style.style():
        fig, (top, bottom) = plt.subplots(
            2, 1, figsize=(_style.WIDTH_IN * 0.6, 4.6), sharex=True,
            gridspec_kw={"height_ratios": [2.2, 1]})
        for probe, f in sorted(result["fit"].items(), key=lambda kv: -float(kv[0])):
            color = PROBE_COLOR.get(probe, "0.3")
            p = _arr(f["pressure_mbar"])
            label = f"{probe} mm" + (f" ({f['curve']})" if f.get("curve") else "")
            top.plot(p, _arr(f["measured_mm"]), linestyle="none", marker="o", markersize=3,
                     markerfacecolor="none", color=color, label=f"{label} measured")
            top.plot(p, _arr(f["fitted_mm"]), color=color, label=f"{label} fitted")
            bottom.plot(p, _arr(f["residual_um"]), marker="o", markersize=2.5,
                        linewidth=0.8, color=color)
        bottom.axhline(0.0, color="0.3", linewidth=0.8)
        top.set_ylabel("deflection M (mm)")
        bottom.set_ylabel("residual (µm)")
        bottom.set_xlabel("suction pressure p (mbar)")
        top.legend(loc="upper left", frameon=False)
        objective = settings["objective"]
        if objective == "weighted":
            objective += f", α = {settings['alpha']:g}"
        e = result["E"]
        e_txt = "n/a" if e["at_estimate"] is None or not np.isfinite(e["at_estimate"]) \
            else f"{e['at_estimate']:.3g} {'' if e['unit'] == '1' else e['unit']}".strip()
        top.set_title(
            f"{result['input']['path']}: {objective}\n"
            f"$X_1^d$ = {est['x1d_mpa']:.4g} MPa, $X_1^h$ = {est['x1h_mpa']:.3g} MPa, "
            f"E = {e_txt}", fontsize=8)
        iv = result.get("intervals")
        if iv:
            top.text(0.98, 0.3, interval_lines(iv, ("X1d", "X1h")), transform=top.transAxes,
                     ha="right", va="center", fontsize=7, bbox=TEXT_BOX)
        fig.tight_layout()
    return fig
