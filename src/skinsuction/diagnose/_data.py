"""The measured data at the fitted points, with the noise the fits are judged against."""

from __future__ import annotations

import math

import numpy as np

from skinsuction.errors import InputError

from ._fit import FitData
from ._settings import Settings
from ._stats import NoiseEstimate, noise_from_differences, noise_from_replicates

__all__ = ["MIN_POINTS", "prepare_data"]

#: Fewest points above 0 mbar per probe that a diagnosis accepts.
MIN_POINTS = 8


def prepare_data(data, probes, settings: Settings):
    """Fitted points per probe and the noise estimate (step 1 of a diagnosis).

    Replicate curves of a probe at the same pressures are averaged (the noise of
    the mean is sd / sqrt(R)); replicates at different pressures are fitted
    point by point.  Points at p = 0 are not fitted (every model gives M(0) = 0;
    a Cutometer zeroes there).

    Parameters
    ----------
    data : MeasuredData
        The measured curves.
    probes : sequence of float
        The probes to fit (those the spaces cover).
    settings : Settings
        ``noise_um`` (given, else estimated from replicates or differences),
        ``model_error_um`` (added in quadrature) and ``degree`` (the fewest points
        a curve needs: ``max(MIN_POINTS, degree + 3)``).

    Returns
    -------
    tuple
        ``(fit_data, noise, info)``: ``{probe: FitData}``, the
        :class:`NoiseEstimate` and, per probe, its curves, replicates and points
        fitted (as in ``report["input"]["curves"]``).

    Raises
    ------
    InputError
        No curve of the given probes, or a curve with too few points above 0 mbar.
    """
    fitted, groups, singles, info = {}, [], [], {}
    for probe in probes:
        curves = data.for_probe(probe)
        if not curves:
            continue
        ps = [c.pressure_mbar for c in curves]
        aligned = len(curves) > 1 and all(
            p.shape == ps[0].shape and np.allclose(p, ps[0]) for p in ps)
        keep = [p > 0 for p in ps]
        for c, k in zip(curves, keep):
            singles.append((c.pressure_mbar[k], c.deflection_mm[k]))
        if aligned:
            y = np.array([c.deflection_mm[keep[0]] for c in curves])
            groups.append(y)
            p, m, n_rep = ps[0][keep[0]], y.mean(axis=0), len(curves)
        else:
            p = np.concatenate([c.pressure_mbar[k] for c, k in zip(curves, keep)])
            m = np.concatenate([c.deflection_mm[k] for c, k in zip(curves, keep)])
            order = np.argsort(p, kind="stable")
            p, m, n_rep = p[order], m[order], 1
        fitted[float(probe)] = (p, m, n_rep, tuple(c.curve for c in curves))
        info[f"{probe:g}"] = {"curves": [c.curve for c in curves], "replicates": len(curves),
                              "averaged": bool(aligned), "points_fitted": int(p.size)}
    if not fitted:
        raise InputError(f"{data.path}: no curve of a probe the spaces cover")
    need = max(MIN_POINTS, settings.degree + 3)
    for probe, (p, *_rest) in fitted.items():
        if p.size < need:
            raise InputError(
                f"{data.path}: the {probe:g} mm curve has {p.size} points above 0 mbar; the "
                f"diagnosis needs at least {need} (the smooth-pattern test fits "
                f"{settings.degree + 1} Legendre terms per probe and the noise needs differences)")
    if settings.noise_um is not None:
        noise = NoiseEstimate(float(settings.noise_um), "given", math.inf, {})
    elif groups:
        noise = noise_from_replicates(groups)
    else:
        noise = noise_from_differences(singles)
    out = {}
    for probe, (p, m, n_rep, ids) in fitted.items():
        sd = math.sqrt(noise.sd_um ** 2 / n_rep + settings.model_error_um ** 2)
        out[probe] = FitData(probe, p, m, sd, ids)
    return out, noise, info
