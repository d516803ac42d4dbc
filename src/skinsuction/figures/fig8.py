"""Figure 8: the ratio approach (paper section 3.3.2, eqs. 11-12).

(a) the test curves M(p) of the 6 mm and 2 mm probes; (b) their ratio
Gamma = M_6mm / M_2mm (eq. 12) and the simulated ratio Theta = Omega_6mm /
Omega_2mm (eq. 11) at the truth and at the median ratio identification;
(c) the 100 ratio identifications as relative errors of X1d and X1h.  Both
test-curve variants: a direct FE run at the test point and the curve taken
from the interpolated space (the paper's).

Examples
--------
>>> import numpy as np, pandas as pd
>>> p = np.arange(0.0, 101.0, 20.0)
>>> curves = pd.DataFrame({"source": "fe", "kind": ["M_6mm", "M_2mm", "Gamma", "Theta_truth",
...                        "Theta_estimate"], "probe_mm": np.nan})
>>> curves = pd.concat([curves.assign(pressure_mbar=x, value=0.01 * x + 0.1) for x in p])
>>> runs = pd.DataFrame({"source": "fe", "objective": "ratio", "repeat": [0, 1],
...                      "x1d": [0.0055, 0.0056], "x1h": [0.00041, 0.0004]})
>>> len(plot_fig8(curves, runs, target=(0.0055, 0.00041)).axes)
3
"""

from __future__ import annotations

import pandas as pd

from skinsuction.figures import _style
from skinsuction.figures.fig4 import SOURCE_STYLE


def plot_fig8(curves: pd.DataFrame, runs: pd.DataFrame, target):
    """Figure 8 from :func:`curves_fig8` and the ratio runs."""
    import matplotlib.pyplot as plt

    sources = [s for s in SOURCE_STYLE if s in set(curves["source"])]
    dash = {"fe": "-", "space": "--"}
    with _style.style():
        fig, axes = plt.subplots(1, 3, figsize=(_style.WIDTH_IN * 1.15, 3.0))
        a, b, c = axes
        for source in sources:
            st = SOURCE_STYLE[source]
            g = curves[curves["source"] == source]
            short = "FE" if source == "fe" else "space"
            for kind, color in (("M_6mm", "#1b6ca8"), ("M_2mm", "#d1495b")):
                k = g[g["kind"] == kind]
                a.plot(k["pressure_mbar"], k["value"], color=color, linestyle=dash[source],
                       label=f"{kind.split('_')[1].replace('mm', ' mm')} ({short})")
            k = g[g["kind"] == "Gamma"]
            b.plot(k["pressure_mbar"], k["value"], linestyle="none", marker=st["marker"],
                   markersize=3, color=st["color"], markerfacecolor=st["markerfacecolor"],
                   label=rf"$\Gamma$ test curve ({short})")
            k = g[g["kind"] == "Theta_estimate"]
            b.plot(k["pressure_mbar"], k["value"], color=st["color"], linestyle=dash[source],
                   linewidth=1.0, label=rf"$\Theta$ at the estimate ({short})")
            r = runs[runs["source"] == source]
            c.plot(100 * (r["x1d"] / target[0] - 1), 100 * (r["x1h"] / target[1] - 1),
                   linestyle="none", marker=st["marker"], markersize=3.2, color=st["color"],
                   markerfacecolor=st["markerfacecolor"], label=short)
        k = curves[(curves["source"] == sources[0]) & (curves["kind"] == "Theta_truth")]
        b.plot(k["pressure_mbar"], k["value"], color="0.2", linestyle=":", linewidth=1.2,
               label=r"$\Theta$ at the truth")
        a.set_xlabel("pressure p (mbar)")
        a.set_ylabel("deflection M (mm)")
        a.set_title("(a) test curves")
        a.legend(frameon=False, fontsize=6.5)
        b.set_xlabel("pressure p (mbar)")
        b.set_ylabel(r"ratio $M_{6mm} / M_{2mm}$")
        b.set_title(r"(b) $\Gamma$ (eq. 12) and $\Theta$ (eq. 11)")
        b.legend(frameon=False, fontsize=6.5)
        c.axhline(0, color="0.2", linewidth=0.8, linestyle="--")
        c.axvline(0, color="0.2", linewidth=0.8, linestyle="--")
        c.set_xlabel(r"error of $X_1^d$ (%)")
        c.set_ylabel(r"error of $X_1^h$ (%)")
        c.set_title(f"(c) {runs.groupby('source').size().max()} ratio identifications")
        c.legend(frameon=False, fontsize=6.5)
        fig.tight_layout()
    return fig


