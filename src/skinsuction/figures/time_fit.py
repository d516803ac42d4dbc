"""Deflection against time, measured and fitted, with residuals (``skinsuction identify``
on time curves).

Examples
--------
>>> result = {"fit": {"6 mm curve": {"probe_mm": 6.0, "time_s": [0, 1, 2, 3],
...                                  "measured_mm": [0, 0.5, 0.6, 0.1],
...                                  "fitted_mm": [0, 0.49, 0.61, 0.1],
...                                  "residual_um": [0, 10, -10, 0],
...                                  "phase": ["rest", "on", "on", "release"]}},
...           "X1d": 0.1, "X1h": 0.004, "g": [0.3], "tau_s": [0.2],
...           "intervals": {"level": 0.95}, "input": {"path": "m.csv"}}
>>> fig = plot_time_fit(result)
>>> [ax.get_ylabel() for ax in fig.axes]
['deflection (mm)', 'residual (µm)']
"""

from __future__ import annotations

import numpy as np

from skinsuction.figures import _style
from skinsuction.figures.fit import PROBE_COLOR, TEXT_BOX, _arr, interval_lines


def plot_time_fit(result: dict):
    """Top: measured deflections (dots) and the fitted model (line) against time, one
    colour per curve; bottom: residuals (µm), points left out of the fit in grey."""
    import matplotlib.pyplot as plt

    with _style.style():
        fig, (top, bottom) = plt.subplots(2, 1, figsize=(_style.WIDTH_IN * 0.8, 4.8),
                                          sharex=True, gridspec_kw={"height_ratios": [2, 1]})
        for i, (label, f) in enumerate(result["fit"].items()):
            color = PROBE_COLOR.get(f"{f['probe_mm']:g}", f"C{i}")
            t = np.asarray(f["time_s"], dtype=float)
            top.plot(t, _arr(f["measured_mm"]), ".", ms=1.5, color=color, alpha=0.5,
                     label=f"{label}, measured")
            top.plot(t, _arr(f["fitted_mm"]), "-", lw=0.9, color="k" if i == 0 else color,
                     label=f"{label}, fitted")
            res = _arr(f["residual_um"])
            bottom.plot(t, res, ".", ms=1.5, color=color)
        bottom.axhline(0.0, color="0.5", lw=0.6)
        top.set_ylabel("deflection (mm)")
        bottom.set_ylabel("residual (µm)")
        bottom.set_xlabel("time (s)")
        top.legend(loc="lower right", fontsize="x-small")
        spectrum = ", ".join(f"g{k} = {g:.3g}, τ{k} = {t:.3g} s"
                             for k, (g, t) in enumerate(zip(result["g"], result["tau_s"]), 1))
        text = (f"X1d = {result['X1d']:.4g} MPa, X1h = {result['X1h']:.4g} MPa (long-time)\n"
                f"{spectrum}")
        iv = result.get("intervals") or {}
        if iv.get("X1d"):
            names = ["X1d", "X1h"] + [k for k in iv if k.startswith(("g_", "tau_"))]
            units = {k: ("s" if k.startswith("tau") else "") for k in names if k[0] in "gt"}
            text += "\n" + interval_lines(iv, names, units).replace("profile likelihood",
                                                                     "Laplace")
        top.text(0.98, 0.5, text, transform=top.transAxes, ha="right", va="center",
                 fontsize="x-small", bbox=TEXT_BOX)
        top.set_title(str(result["input"]["path"]), fontsize="small")
        fig.tight_layout()
    return fig
