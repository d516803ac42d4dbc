"""What a mode 1 or mode 2 measurement will tell: intervals from the time model's
Fisher information on noise-free curves.

The skin's time curves are the viscoelastic fast path's (the identification's own
model, :class:`~skinsuction.identify.TimeCurveModel`: the space's neo-Hookean rays
driven by the effective pressure of a one-term spectrum) at the design's suction
history, sampled at its rate; each point's sd is the identification's (the noise, the
fast path's error per phase, the space's accuracy), and the reading step's rounding
enters as the identification's correlated rounding terms.  At the truth, the
Gauss-Newton intervals of :func:`~skinsuction.identify.laplace_intervals` (the ones
``identify`` reports for time curves, with its correlated model-error term) are the
intervals a typical measurement gets.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np

from ._box import relative_halfwidth

#: the spectrum's reported quantities (one term) and their columns in a skin's row
SPECTRUM = {"g_1": "g_1", "tau_1": "tau_1_s"}


def time_curves(space, theta, design, sigma_mm: float) -> list:
    """The noise-free curves of ``theta`` (log10 X1d, log10 X1h/X1d, log10 g, log10 tau)
    on every probe of ``design``, as :class:`~skinsuction.identify.TimeFitData`."""
    from skinsuction.identify import TimeCurveModel, time_fit_data

    t, p, phase = design.history()
    rays = {q: space for q in design.probes_mm}
    blank = [time_fit_data(f"{q:g} mm", q, t, p, np.zeros_like(t), phase, sigma_mm)
             for q in design.probes_mm]
    curves = TimeCurveModel(rays, blank, terms=1)(np.asarray(theta, float)[None, :])
    return [time_fit_data(f"{q:g} mm", q, t, p, m[0], phase, sigma_mm,
                          resolution_mm=design.resolution_mm)
            for q, m in zip(design.probes_mm, curves)]


def predict_time(skin: dict, design, space, settings) -> dict:
    """``<P>_halfwidth`` and ``<P>_bounded`` of X1d, X1h (long-time), g_1 and tau_1;
    ``beyond_space`` and a note where the curves leave the space's rays."""
    from skinsuction.identify import TimeCurveModel, evaluate_time_fit, laplace_intervals

    x1d = float(skin["x1d_mpa"])
    truth = {"X1d": x1d, "X1h": x1d * float(skin["x1h_ratio"])}
    truth.update({k: float(skin[col]) for k, col in SPECTRUM.items()})
    theta = np.log10([x1d, float(skin["x1h_ratio"]), truth["g_1"], truth["tau_1"]])
    # the noise alone: the identification of time curves models the reading step's
    # rounding as correlated terms of its own (rounding_terms), not as white noise
    sigma_mm = 1e-3 * math.hypot(design.noise_um, settings.model_error_um)
    data = time_curves(space, theta, design, sigma_mm)
    if not all(np.isfinite(d.deflection_mm).all() for d in data):
        return {"beyond_space": True, "notes": (
            "the neo-Hookean rays stop before the suction's top at this skin (the FE "
            "model finds no equilibrium there)")}
    rays = {q: space for q in design.probes_mm}
    fit = evaluate_time_fit(TimeCurveModel(rays, data, terms=1), theta)
    iv = laplace_intervals(rays, data, fit, level=settings.level)
    row = {}
    for k, v in truth.items():
        ns = SimpleNamespace(**iv[k]) if k in iv else None
        row[f"{k}_halfwidth"], row[f"{k}_bounded"] = relative_halfwidth(k, v, ns)
    row["time_points"] = int(sum(d.n for d in data))
    return row


def time_notes(design, name=None) -> list:
    """What a time design's row leaves out, in words (about ``name``, default the
    design's)."""
    notes = [f"{name or design.name}: intervals from the fast path's Fisher information at the "
             "truth (one Prony term, the identification's model and sd per point); the "
             "causes are not predicted for time curves"]
    if any(design.given.values()):
        notes.append("a thickness sd is not propagated into the intervals of time curves "
                     "(as in identify): the layers are taken as given exactly")
    return notes
