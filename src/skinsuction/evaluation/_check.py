"""Direct FE runs at the parameters a diagnosis identified (Figure 6, space accuracy).

The fits of the diagnosis read interpolated ray spaces; :func:`fe_check`
re-runs the FE model at the fitted parameters of the baseline and of the chosen
(or best) candidate, at the measured pressures, so that Figure 6 shows true
simulated curves and the E of a direct FE run next to the E of the fit.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from skinsuction.space import Cause

__all__ = ["fe_check", "models_of_figure6"]


def models_of_figure6(report: dict):
    """(label, model name, parameters, cause dict or None) of Figure 6's panels (a), (b).

    Panel (b) is the chosen cause, or the candidate of lowest BIC when the
    verdict is ``none`` (then labelled "best candidate, not retained").
    """
    b = report["baseline"]
    out = [("neo-Hookean", "neo_hookean", b["parameters"], None)]
    cands = sorted(report["candidates"], key=lambda c: c["bic"])
    named = next((c for c in cands if c["cause"] == report["cause"]), None)
    if named is not None and report.get("extended"):
        out.append((f"extended: {named['cause']}", named["cause"], named["parameters"], named))
    elif cands:
        c = cands[0]
        out.append((f"best candidate, not retained: {c['cause']}", c["cause"],
                    c["parameters"], c))
    return out


def _keywords(params: dict, cand: dict | None, causes: dict | None) -> dict:
    kw = {"x1d": params["X1d"], "x1h": params["X1h"]}
    if cand is not None:
        sym = cand["extra_parameter"]["symbol"]
        keyword = None
        if causes and cand["cause"] in causes:
            keyword = causes[cand["cause"]].keyword
        else:
            keyword = {"X2d": "x2d", "t_d": "t_d", "lambda0": "prestretch"}.get(sym)
        if keyword is None:
            raise ValueError(f"unknown model keyword of {cand['cause']!r}")
        kw[keyword] = params[sym]
    return kw


def fe_check(report: dict, mesh=None, bottom="fixed", causes: dict | None = None):
    """FE curves at the fitted parameters of Figure 6's models, at the measured pressures.

    Returns a long DataFrame: ``panel, model, probe_mm, pressure_mbar,
    measured_mm, fe_mm, interpolated_mm, converged`` plus the parameters.
    """
    from skinsuction.model import Skin, simulate

    rows = []
    for panel, (label, name, params, cand) in enumerate(models_of_figure6(report)):
        kw = _keywords(params, cand, causes)
        fit = report["baseline"] if cand is None else cand["fit"]
        for probe, d in report["data"].items():
            p = np.asarray(d["pressure_mbar"], dtype=float)
            grid = np.concatenate([[0.0], p]) if p[0] > 0 else p
            c = simulate(Skin.two_layer(**kw, bottom=bottom), float(probe), pressures_mbar=grid,
                         mesh=dict(mesh or {}))
            fe = c.deflection_mm[-p.size:]
            rows.append(pd.DataFrame({
                "panel": "ab"[panel], "label": label, "model": name, "probe_mm": float(probe),
                "pressure_mbar": p, "measured_mm": np.asarray(d["measured_mm"], dtype=float),
                "fe_mm": fe,
                "interpolated_mm": np.array([np.nan if v is None else v
                                             for v in fit["fitted_mm"][probe]], dtype=float),
                "converged": bool(c.converged),
                **{f"param_{k}": v for k, v in params.items()}}))
    return pd.concat(rows, ignore_index=True)


def e_um(residual_um) -> float:
    """Eq. 7 of the paper on a residual vector (µm)."""
    r = np.asarray(residual_um, dtype=float)
    return math.sqrt(float((r ** 2).sum())) / r.size if r.size else math.nan


_ = Cause  # re-exported type for annotations in callers
