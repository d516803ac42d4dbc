"""Time curves: which layer creeps, and a first cycle that departs (preconditioning).

The layer test weighs the final model's spectrum shared by both layers against one
spectrum per layer (two apertures needed); :func:`cycle_pattern` describes in words a
first cycle no model holds.  The model itself is built in :mod:`._time_effects`.
"""

from __future__ import annotations

import math

import numpy as np

from ._creep import VISCOELASTIC_CREEP
from ._stats import bic
from ._time_effects import EffectFitter, TimeModel

__all__ = ["cycle_pattern", "layer_test", "LAYER_RATIO"]


def cycle_pattern(data, fitted, sd_factor: float = 3.0) -> list:
    """Words for a first cycle that departs from the later ones (preconditioning).

    Per curve with two or more holds (``on`` phases), the mean residual of each
    hold; the first departs when it differs from the later holds' mean by more
    than ``sd_factor`` times the spread of the later holds (or their standard
    error, whichever is larger) and by more than the noise sd.

    Parameters
    ----------
    data : list of TimeFitData
    fitted : list of ndarray
        The final model's deflections (mm) per curve.

    Returns
    -------
    list of str
    """
    out = []
    for d, m in zip(data, fitted):
        on = np.concatenate([[False], d.phase == "on", [False]]).astype(int)
        edges = np.flatnonzero(np.diff(on))
        holds = list(zip(edges[0::2], edges[1::2]))
        if len(holds) < 2:
            continue
        r = 1e3 * (d.deflection_mm - np.asarray(m, dtype=float))
        means = np.array([np.mean(r[a:b]) for a, b in holds])
        later = means[1:]
        se = float(np.mean([np.std(r[a:b]) / math.sqrt(max(b - a, 1)) for a, b in holds[1:]]))
        spread = float(np.std(later)) if later.size > 1 else 0.0
        gap = float(means[0] - later.mean())
        if abs(gap) > sd_factor * max(spread, se) and abs(gap) > 1e3 * d.noise_sd_mm:
            out.append(f"{d.label}: the first cycle departs from the later ones by "
                       f"{gap:+.1f} µm in its hold (the later holds agree within "
                       f"{max(spread, se):.1f} µm): the skin changes over the first cycle "
                       "(preconditioning), which no model here holds")
    return out


#: How much more one layer's g must be than the other's to name that layer alone.
LAYER_RATIO = 3.0


def _creeping(iv: dict, decisive: bool) -> str:
    """The layer test's answer from the per-layer g intervals.

    ``"dermis"`` or ``"hypodermis"``: the spectra differ (``decisive``), that layer's g
    exceeds 0.05 at its lower end (or its estimate is at the spectrum's upper edge) and
    the other's estimate by :data:`LAYER_RATIO`; ``"both"``: both g's lower ends exceed
    0.05; else ``"cannot tell"``.

    >>> iv = lambda e, lo, hi, up=False: {"estimate": e, "lower": lo, "upper": hi,
    ...                                   "upper_open": up}
    >>> _creeping({"g_dermis": iv(0.03, 0.001, 0.8), "g_hypodermis": iv(5, 0.001, 5, True)},
    ...           True)
    'hypodermis'
    >>> _creeping({"g_dermis": iv(0.4, 0.2, 0.6), "g_hypodermis": iv(0.5, 0.3, 0.8)}, True)
    'both'
    >>> _creeping({"g_dermis": iv(0.03, 0.001, 0.8), "g_hypodermis": iv(5, 0.001, 5, True)},
    ...           False)
    'cannot tell'
    """
    gd, gh = iv["g_dermis"], iv["g_hypodermis"]

    def creeps(g):
        return g["lower"] > 0.05 or (g.get("upper_open") and g["estimate"] > 0.05)

    for name, g, other in (("dermis", gd, gh), ("hypodermis", gh, gd)):
        if decisive and creeps(g) and g["estimate"] > LAYER_RATIO * other["estimate"]:
            return name
    if gd["lower"] > 0.05 and gh["lower"] > 0.05:
        return "both"
    return "cannot tell"


def layer_test(fitter: EffectFitter, final: TimeModel, settings) -> dict:
    """Which layer creeps: the final model's spectrum shared by both layers against one
    spectrum per layer (one term each).  With ``settings.fe_correction`` each fit is
    corrected by FE time solves with a spectrum per layer and held to the data's own
    model error; without, both are under the per-layer fast path's larger model error
    (:data:`skinsuction.identify.MODEL_ERROR_LAYERS`: a screen).

    Two probes of different apertures are needed: a small one sees mostly the dermis, a
    large one the hypodermis too (the hypodermis's share of the compliance, ``beta``,
    is reported per probe).  With one aperture the test is not run, and says why.

    Parameters
    ----------
    fitter : EffectFitter
    final : TimeModel
        The selection's final model; it must hold creep.
    settings : Settings

    Returns
    -------
    dict
        ``tested`` (bool), ``reason``; when tested: ``delta_bic`` (per layer minus
        shared), ``decisive`` (the spectra differ), ``creeping`` (:func:`_creeping`),
        ``elastic_check`` (does the final model's elastic effect still earn its place
        with a spectrum per layer?), the per-layer ``parameters`` and ``intervals``,
        ``beta`` per probe, ``model_error``, ``fe_correction`` (per fit).
    """
    from skinsuction.identify import (MODEL_ERROR_LAYERS, TimeCurveModel, fit_data_of,
                                      fit_time_model, laplace_intervals)

    if VISCOELASTIC_CREEP not in final.effects:
        return {"tested": False, "reason": "no creep named"}
    if len({d.probe_mm for d in fitter.data}) < 2:
        return {"tested": False,
                "reason": "one probe cannot tell which layer creeps: its curve sees one "
                          "mix of the layers (measure a second aperture, e.g. 2 + 8 mm)"}
    corrected = bool(settings.fe_correction)
    # corrected by FE time solves, the per-layer model is held to the data's own model
    # error; the fast path alone needs its larger one
    data = (fitter.data if corrected else
            [fit_data_of(c, noise_sd_mm=d.noise_sd_mm, model_error=MODEL_ERROR_LAYERS)
             for c, d in zip(fitter.prep["curves"], fitter.data)])
    rays = final.rays
    cause = final.elastic_cause
    k0 = 2 + (cause is not None)
    theta = np.asarray(final.fit.theta, dtype=float)
    start = theta[:k0 + 2]  # the first (fastest) creep term of the final model
    seed = np.random.SeedSequence(int(settings.seed), spawn_key=(99,))
    s_shared, s_layers = seed.spawn(2)
    records = {}

    def fit(name, rays_, start_, seed_, per_layer, cause_):
        f = fit_time_model(rays_, data, terms=1, seed=seed_, repeats=settings.repeats,
                           starts=[start_], layers=per_layer)
        if not corrected:
            return f, data
        key = (VISCOELASTIC_CREEP,) + ((cause_,) if cause_ else ())
        f, fd, records[name] = fitter._corrected(f, rays_, cause_, key, data, per_layer)
        return f, fd

    shared, _ = fit("shared", rays, start, s_shared, False, cause)
    layered_start = np.concatenate([shared.theta, shared.theta[k0:k0 + 2]])
    layers, layers_data = fit("per_layer", rays, layered_start, s_layers, True, cause)
    b_shared = bic(shared.chi2, shared.n_params, shared.n_points)
    b_layers = bic(layers.chi2, layers.n_params, layers.n_points)
    delta = float(b_layers - b_shared)
    iv = laplace_intervals(rays, layers_data, layers, level=settings.level)
    p = layers.parameters
    model = TimeCurveModel(rays, data, 1, layers=True)
    beta = {f"{d.probe_mm:g}": float(model.hypodermis_share(layers.theta[None], d.probe_mm,
                                                            float(d.pressure_mbar.max()))[0])
            for d in data}
    decisive = bool(delta <= settings.delta_bic)  # the layers' spectra differ
    creeping = _creeping(iv, decisive)
    # does the elastic effect still earn its place once each layer has its spectrum?
    elastic_check = None
    if decisive and cause is not None:
        plain, _ = fit("without_elastic_effect", fitter.rays[None], np.delete(layers.theta, 2),
                       seed.spawn(1)[0], True, None)
        d_plain = float(b_layers - bic(plain.chi2, plain.n_params, plain.n_points))
        elastic_check = {"effect": cause, "delta_bic_without": d_plain,
                         "earns_its_place": bool(d_plain <= settings.delta_bic),
                         "without_it": {"chi2": float(plain.chi2),
                                        "parameters": plain.parameters}}
    return {"tested": True, "delta_bic": delta, "decisive": decisive, "creeping": creeping,
            "elastic_check": elastic_check,
            "parameters": {k: p[k] for k in ("g_dermis", "tau_s_dermis", "g_hypodermis",
                                             "tau_s_hypodermis")},
            "intervals": {k: iv[k] for k in ("g_dermis", "tau_dermis", "g_hypodermis",
                                             "tau_hypodermis")},
            "shared": {"chi2": float(shared.chi2), "bic": float(b_shared),
                       "parameters": shared.parameters},
            "chi2": float(layers.chi2), "bic": float(b_layers), "beta": beta,
            "model_error": (dict(data[0].model_error) if corrected
                            else dict(MODEL_ERROR_LAYERS)),
            "fe_correction": records or None,
            "reason": ("a spectrum per layer against one for both, each fit corrected by FE "
                       "time solves (docs/effects.md)" if corrected else
                       "a spectrum per layer against one for both, each under the per-layer "
                       "fast path's model error (2 % of the curve; docs/effects.md)")}
