"""Figures of a diagnosis (``skinsuction diagnose``): fit overlay, residuals, gain.

Each function takes the report dict of :func:`skinsuction.diagnose.diagnose`
and returns a Matplotlib figure.
"""

from __future__ import annotations

import numpy as np

from skinsuction.figures import _style
from skinsuction.figures.fit import PROBE_COLOR, TEXT_BOX, interval_lines

#: Line style of the models: the first effect alone where a second was added.
MODEL_STYLE = {"baseline": {"linestyle": "--", "color": "0.35"},
               "first": {"linestyle": ":", "color": "#c05a00"},
               "extended": {"linestyle": "-", "color": "#2e933c"}}


def _arr(values):
    return np.array([np.nan if v is None else v for v in values], dtype=float)


def _measured(report):
    """{probe: measured mm} of the fitted points (replicates averaged)."""
    return {p: _arr(d["measured_mm"]) for p, d in report["data"].items()}


def _pressures(report):
    return {p: _arr(d["pressure_mbar"]) for p, d in report["data"].items()}


def _chosen(report):
    """The model the verdict names (two effects: the pair's fit); None for `none`, and for
    `beyond_space` when the baseline itself sits at an edge (no candidate stands behind
    the verdict)."""
    added = (report.get("second_effect") or {}).get("added")
    if added:
        return {**added, "cause": " + ".join(added["effects"])}
    return next((c for c in report["candidates"] if c["cause"] == report["cause"]), None)


def _first(report):
    """The first effect's own fit, where a second effect was added to it (else None)."""
    if not (report.get("second_effect") or {}).get("added"):
        return None
    return next(c for c in report["candidates"] if c["cause"] == report["cause"])


#: Units of the fitted parameters.
UNIT = {"X1d": "MPa", "X1h": "MPa", "X2d": "MPa", "t_d": "mm", "t_h": "mm"}


def _params_label(params):
    unit = UNIT
    sym = {"X1d": "$X_1^d$", "X1h": "$X_1^h$", "X2d": "$X_2^d$", "t_d": "$t_d$",
           "t_h": "$t_h$", "lambda0": r"$\lambda_0$"}
    return ", ".join(f"{sym.get(k, k)} = {v:.3g}{' ' + unit[k] if k in unit else ''}"
                     for k, v in params.items())


def plot_fit(report: dict, title: str | None = None):
    """Measured deflections and the fitted curves (baseline and chosen cause) per probe."""
    import matplotlib.pyplot as plt

    meas = _measured(report)
    press = _pressures(report)
    chosen = _chosen(report)
    probes = sorted(meas, key=lambda p: -float(p))
    with _style.style():
        fig, axes = plt.subplots(1, len(probes), figsize=(_style.WIDTH_IN, 3.0), squeeze=False)
        for ax, probe in zip(axes[0], probes):
            p = press[probe]
            ax.plot(p, meas[probe], linestyle="none", marker="o", markersize=2.8,
                    markerfacecolor="none", color=PROBE_COLOR.get(probe, "0.3"),
                    label="measured")
            ax.plot(p, _arr(report["baseline"]["fitted_mm"][probe]),
                    label=f"neo-Hookean, E = {report['baseline']['E_um']:.2g} µm",
                    **MODEL_STYLE["baseline"])
            first = _first(report)
            if first is not None:
                ax.plot(p, _arr(first["fit"]["fitted_mm"][probe]),
                        label=f"{first['cause']} alone, E = {first['E_um']:.2g} µm",
                        **MODEL_STYLE["first"])
            if chosen is not None:
                ax.plot(p, _arr(chosen["fit"]["fitted_mm"][probe]),
                        label=f"{chosen['cause']}, E = {chosen['E_um']:.2g} µm",
                        **MODEL_STYLE["extended"])
            ax.set_title(f"{probe} mm probe")
            ax.set_xlabel("suction pressure p (mbar)")
            ax.set_ylabel("apex deflection M (mm)")
            ax.legend(loc="upper left", frameon=False, fontsize=6.5 if first is not None else None)
        fit_ci = (chosen or {}).get("intervals") or report["baseline"].get("intervals")
        if fit_ci and "error" not in fit_ci:
            names = [k for k in fit_ci if k in UNIT or k == "lambda0"]
            axes[0][-1].text(0.98, 0.3, interval_lines(fit_ci, names, {**UNIT, "lambda0": ""}),
                             transform=axes[0][-1].transAxes, ha="right", va="center",
                             fontsize=6.5, bbox=TEXT_BOX)
        effects = report.get("effects") or []
        fig.suptitle(title or (f"effects: {' + '.join(effects)}" if len(effects) > 1
                               else f"cause: {report['cause']}"), fontsize=9)
        fig.tight_layout()
    return fig


def plot_residuals(report: dict):
    """Residuals (measured - simulated) against pressure per probe, with the noise band."""
    import matplotlib.pyplot as plt

    press = _pressures(report)
    chosen = _chosen(report)
    probes = sorted(press, key=lambda p: -float(p))
    sig = report["noise"]["sigma_fitted_um"]
    with _style.style():
        fig, axes = plt.subplots(1, len(probes), figsize=(_style.WIDTH_IN, 2.8), squeeze=False,
                                 sharey=True)
        for ax, probe in zip(axes[0], probes):
            p = press[probe]
            s = sig[probe]
            ax.axhspan(-s, s, color="0.85", zorder=0, label=f"±1 noise sd ({s:.2g} µm)")
            ax.axhline(0, color="0.3", linewidth=0.8)
            base = report["baseline"]
            ax.plot(p, _arr(base["residual_um"][probe]), marker="o", markersize=2.5,
                    linewidth=0.8, label=f"neo-Hookean (pattern p = "
                    f"{base['misfit_test']['per_probe'][probe]['p_value']:.1g})",
                    **MODEL_STYLE["baseline"])
            if chosen is not None:
                t = chosen["fit"]["misfit_test"]["per_probe"][probe]
                ax.plot(p, _arr(chosen["fit"]["residual_um"][probe]), marker="s",
                        markersize=2.2, linewidth=0.8,
                        label=f"{chosen['cause']} (p = {t['p_value']:.1g})",
                        **MODEL_STYLE["extended"])
            ax.set_title(f"{probe} mm probe")
            ax.set_xlabel("suction pressure p (mbar)")
            ax.legend(loc="best", frameon=False, fontsize=6.5)
        axes[0, 0].set_ylabel("residual, measured − simulated (µm)")
        fig.tight_layout()
    return fig


def plot_gain(report: dict):
    """Per candidate: delta BIC (with the threshold) and E / E_baseline, holdout ratio."""
    import matplotlib.pyplot as plt

    cands = sorted(report["candidates"], key=lambda c: c["bic"])
    names = [c["cause"] for c in cands]
    thr = report["settings"]["delta_bic"]
    with _style.style():
        fig, (a, b) = plt.subplots(1, 2, figsize=(_style.WIDTH_IN, 2.6))
        y = np.arange(len(cands))
        colors = ["#2e933c" if c["cause"] == report["cause"] else
                  ("#e0a100" if c["decisive"] else "0.6") for c in cands]
        a.barh(y, [c["delta_bic"] for c in cands], color=colors)
        a.axvline(thr, color="#d1495b", linestyle="--", linewidth=0.9,
                  label=f"decisive: ΔBIC ≤ {thr:g}")
        a.axvline(0, color="0.3", linewidth=0.8)
        a.set_yticks(y, names)
        a.invert_yaxis()
        a.set_xlabel("ΔBIC vs neo-Hookean (negative: better)")
        a.legend(loc="lower right", frameon=False, fontsize=6.5)
        w = 0.38
        b.barh(y - w / 2, [c["E_ratio"] for c in cands], height=w, color=colors,
               label="E / E(neo-Hookean), joint fit")
        hold = [np.nan if c["holdout_ratio"] is None else c["holdout_ratio"] for c in cands]
        if not np.all(np.isnan(hold)):
            b.barh(y + w / 2, hold, height=w, color=colors, alpha=0.45, hatch="//",
                   label="cross-probe holdout E ratio")
        b.axvline(1.0, color="0.3", linewidth=0.8)
        b.set_yticks(y, names)
        b.invert_yaxis()
        b.set_xlabel("error ratio (< 1: better)")
        b.legend(loc="lower right", frameon=False, fontsize=6.5)
        fig.suptitle(f"cause: {report['cause']}   (green: named; orange: decisive ΔBIC but a "
                     "misfit is left or it lost a tie; grey: not decisive)", fontsize=8)
        fig.tight_layout()
    return fig
