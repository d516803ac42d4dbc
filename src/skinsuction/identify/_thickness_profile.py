"""The profile of a ramp's fit over the given layer thicknesses (their sd).

:func:`._ramp_intervals.thickness_uncertainty` fits the moduli again at other
thicknesses, read off the geometry spaces whatever their error estimate (no FE ray
for a likelihood's tail: :meth:`skinsuction.space.LoadedSpace.read_only_at`):
:func:`_profile_fits` at +-2 and +-3 sd of one thickness, or at the corners of +-1 sd
of both; :func:`_at_mode` at the posterior's mode over the thickness lattice and along
the valley through it.  :func:`_profiled` turns every fit into the intervals' reach
(the union of each fit's own, shrunk by its rise above the least).
"""

from __future__ import annotations

import math

import numpy as np

from skinsuction.space import THICKNESS_RESOLUTION_MM

from ._thickness_mode import posterior_mode


#: The profile over the given thicknesses reaches this far (in sd of the given ones)
#: beyond the fits at +-1 sd: the chi^2 of the curves in a thin dermis is often flat on
#: one side and steep on the other, which the quadratic through +-1 sd reads as a sharp
#: minimum; and with both thicknesses given, a thicker dermis over a thinner hypodermis
#: can fit as well as the given pair (a valley across the axes).
TAIL_SD = (2.0, 3.0)


def _profile_fits(setup, fit_at, sds, points, scale) -> list:
    """More fits of the posterior over the given thicknesses, read off the geometry
    spaces whatever their error estimate (no FE ray: a likelihood's tail needs no
    0.2 %): with one thickness given, at +-2 and +-3 sd; with both, at the four
    corners of +-1 sd and then at 2 and 3 sd either way along the valley of the
    quadratic through the nine fits, from the best of them.  Returns the
    thicknesses left out, beyond the simulated geometry."""
    geometry, space, probes, edge = setup.geometry, setup.space, setup.probes, []
    keys = list(sds)

    def at(s):  # the fit at s sd (a vector over ``keys``), if the grid holds it
        g = geometry
        for k, v in zip(keys, s):
            g = g.shifted(k, v * sds[k])
        moved = (space.read_only_at(g, probes)
                 if all(getattr(g, k) > 0 for k in keys) else None)
        if moved is None:
            edge.append(", ".join(f"{k} = {getattr(g, k):.3g} mm" for k in keys))
        else:
            fit_at(g, moved)

    if len(keys) == 1:
        for v in (-TAIL_SD[1], -TAIL_SD[0], TAIL_SD[0], TAIL_SD[1]):
            at([v])
        return edge
    for corner in ((1, 1), (1, -1), (-1, 1), (-1, -1)):
        at(corner)
    s, d = _posterior_samples(points, geometry, sds, scale)
    near = np.all(np.abs(s) <= 1 + 1e-9, axis=1) & np.isfinite(d)
    if near.sum() < 6:
        return edge
    x, y = s[near].T
    A = np.column_stack([x * x, y * y, x * y, x, y, np.ones_like(x)])
    a, b, c = np.linalg.lstsq(A, d[near], rcond=None)[0][:3]
    w, v = np.linalg.eigh(np.array([[a, c / 2], [c / 2, b]]))
    valley = v[:, int(np.argmin(w))]
    best = s[near][int(np.argmin(d[near]))]
    for t in (-TAIL_SD[1], -TAIL_SD[0], TAIL_SD[0], TAIL_SD[1]):
        at(best + t * valley)
    return edge


#: Fits along the valley through the posterior's mode, where the Gauss-Newton Hessian
#: puts these multiples of the intervals' threshold above it.
VALLEY_RISES = (0.5, 1.0, 2.0)


def _at_mode(setup, fit_at, sds, scale, q, fits, out, est, remarks):
    """The estimate at the posterior's mode over the given thicknesses
    (:func:`._thickness_mode.posterior_mode`, fits read off the geometry spaces,
    within 3 sd), where its -2 log posterior is below the estimate's; then fits along
    the valley through the mode, at :data:`VALLEY_RISES` times the threshold ``q``, for
    the profile (``fits``: the fits' points and residual vectors, extended in place)."""
    points, vectors = fits
    geometry, keys, unit = setup.geometry, list(sds), THICKNESS_RESOLUTION_MM
    sd_units = np.array([sds[k] / unit for k in keys])
    found = {}

    def fit(n):
        g = geometry
        for k, v in zip(keys, n):
            g = g.shifted(k, v * unit)
        moved = (setup.space.read_only_at(g, setup.probes)
                 if all(getattr(g, k) > 0 for k in keys) else None)
        if moved is None:
            return None
        found[n] = fit_at(g, moved)[0]
        return np.concatenate([vectors[-1] / math.sqrt(scale), np.asarray(n) / sd_units])

    s, d = _posterior_samples(points, geometry, sds, scale)
    at_est = [i for i, (_, x, _) in enumerate(points) if np.allclose(x, est, rtol=1e-12)]
    d_est = float(d[at_est[0]] if at_est else d[0])
    bound = np.round(TAIL_SD[1] * sd_units)
    mode = posterior_mode(fit, sd_units, s[int(np.nanargmin(d))] * sd_units, bound)
    if mode.offset in found and mode.value < d_est - 1e-9:
        est = np.asarray(found[mode.offset], dtype=float)
        for key, n in zip(keys, mode.offset):
            name = {"t_d": "dermis_thickness", "t_h": "hypodermis_thickness"}[key]
            out[name]["estimate_at_mm"] = getattr(geometry, key) + n * unit
            if n:
                remarks[key] = "; the mode of the posterior over the thicknesses"
            else:
                remarks.pop(key, None)
    valley = mode.valley()
    if valley is not None and q > 0:
        u, rise = valley
        for f in VALLEY_RISES:
            t = math.sqrt(f * q / rise) if rise > 0 else float(np.max(bound))
            for side in (1, -1):
                n = tuple(int(v) for v in np.clip(np.round(np.asarray(mode.offset) + side * t * u),
                                                  -bound, bound))
                if n not in found:
                    fit(n)
    return est


def _posterior_samples(points, geometry, sds, scale):
    """``(s, D)``: each fit's thicknesses in sd of the given ones, and ``-2 log`` of the
    posterior there (its chi^2 over the misfit scale plus the Gaussian priors)."""
    s = np.array([[(getattr(g, k) - getattr(geometry, k)) / sd for k, sd in sds.items()]
                  for g, _, _ in points], dtype=float).reshape(len(points), len(sds))
    d = np.array([c for _, _, c in points], dtype=float) / scale + np.sum(s * s, axis=1)
    return s, d


def _profiled(intervals, points, geometry, sds, est0) -> dict:
    """Each modulus's interval from the profile over the thicknesses, in log: at every
    fit ``p`` (a thickness, its moduli ``X_p`` and chi^2 ``c_p``) the posterior's rise
    ``D_p = c_p / s + sum ((t - t0) / sd)^2`` above its least (``s`` the misfit scale),
    and about ``X_p`` the interval of the estimate's own half-widths ``h`` shrunk by
    ``sqrt(1 - D_p / q)`` (``q`` the threshold): the union over the fits.  Where the
    chi^2 is quadratic in the thickness and the moduli linear in it, this is the
    Laplace widening along one thickness; where not, it follows the chi^2."""
    scale = float(intervals.get("misfit_scale") or 1.0)
    q = float(intervals.get("delta_chi2_threshold") or 0.0) / scale
    if not points or q <= 0:
        return {}
    rise = _posterior_samples(points, geometry, sds, scale)[1]
    least = float(np.nanmin(rise))
    out = {}
    for i, name in enumerate(("X1d", "X1h")):
        iv = intervals.get(name)
        if not iv:
            continue
        e0 = float(est0[i])
        h = {side: abs(math.log(iv[side] / e0)) if iv[side] and iv[side] > 0 else None
             for side in ("lower", "upper")}
        lo = hi = None
        for (_, x, _), r in zip(points, rise):
            if not (math.isfinite(r) and r - least < q and x[i] > 0):
                continue
            shrink = math.sqrt(1.0 - (r - least) / q)
            if h["lower"] is not None:
                v = math.log(x[i]) - h["lower"] * shrink
                lo = v if lo is None else min(lo, v)
            if h["upper"] is not None:
                v = math.log(x[i]) + h["upper"] * shrink
                hi = v if hi is None else max(hi, v)
        out[name] = (None if lo is None else math.exp(lo), None if hi is None else math.exp(hi))
    return out


def _widen_to(intervals, profiled, edge) -> None:
    """The intervals widened to the profile's where it reaches further (in place)."""
    for name, (lo, hi) in profiled.items():
        iv = intervals[name]
        if lo is not None and iv["lower"] and lo < iv["lower"]:
            iv["lower"] = lo
        if hi is not None and iv["upper"] and hi > iv["upper"]:
            iv["upper"] = hi
    intervals["notes"] = list(intervals.get("notes", [])) + [
        "the intervals also reach as far as the profile of the fits over the given "
        "thicknesses (to 3 sd) takes them"
        + (f"; left out beyond the simulated geometry: {', '.join(edge)}" if edge else "")]
