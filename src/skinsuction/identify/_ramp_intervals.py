"""The intervals of a pressure ramp's estimate (:func:`.measured_fit.identify_data`).

The noise of the fitted curves (:func:`estimate_noise`), the profile-likelihood
intervals of X1d and X1h on the likelihood of :mod:`._space_error`
(:func:`noise_and_intervals`), widened for the sd of given layer thicknesses
(:func:`thickness_uncertainty`).  Both append their warnings to the setup's.
"""

from __future__ import annotations

import math

import numpy as np

from skinsuction.space import THICKNESS_RESOLUTION_MM

from ._intervals import profile_intervals
from ._polish import polish
from ._ramp_steps import RampSetup, make_objective
from ._thickness_profile import _at_mode, _profile_fits, _profiled, _widen_to
from ._space_error import MODEL_ERROR_RELATIVE, likelihood_residuals

__all__ = ["estimate_noise", "noise_and_intervals", "thickness_uncertainty"]


def estimate_noise(curves, data, noise_um):
    """Noise of the fitted curves: given, from replicates of their probes, or differences."""
    from skinsuction.noise import NoiseEstimate, noise_from_differences, noise_from_replicates

    if noise_um is not None:
        return NoiseEstimate(float(noise_um), "given", math.inf, {})
    groups = []
    for p in curves:
        reps = data.for_probe(p)
        ps = [c.pressure_mbar for c in reps]
        if len(reps) > 1 and all(q.shape == ps[0].shape and np.allclose(q, ps[0]) for q in ps):
            groups.append(np.array([c.deflection_mm for c in reps]))
    if groups:
        return noise_from_replicates(groups)
    return noise_from_differences([(c.pressure_mbar[c.pressure_mbar > 0],
                                    c.deflection_mm[c.pressure_mbar > 0])
                                   for c in curves.values()])


def noise_and_intervals(setup: RampSetup, theta, noise_um, level: float, correlated: bool):
    """The noise of the curves and the profile-likelihood intervals of X1d and X1h.

    Parameters
    ----------
    setup : RampSetup
    theta : array_like
        The estimate (the objective's coordinates).
    noise_um : float or None
        The noise sd given (µm), else estimated (:func:`estimate_noise`).
    level : float
        Confidence level.
    correlated : bool
        Whether the space's error enters each probe as a correlated term (on the
        scale-free space; :data:`.measured_fit.SPACE_ERROR_CORRELATED`).

    Returns
    -------
    noise : dict or None
        The noise estimate (None, with a warning, if it cannot be estimated).
    intervals : dict or None
        The intervals (None, with a warning, without a noise or a likelihood).
    """
    obj, objective, curves, warnings = setup.obj, setup.objective, setup.curves, setup.warnings
    scale_free = setup.scale_free
    try:
        noise = estimate_noise(curves, setup.data, noise_um)
    except ValueError as err:
        warnings.append(f"no intervals: the noise cannot be estimated ({err}); "
                        "give it with --noise-um")
        return None, None
    if noise.sd_um <= 1e-6:
        warnings.append("no intervals: the estimated noise is 0 (are the deflections "
                        "rounded or synthetic?); give it with --noise-um")
        return noise.to_dict(), None
    x1d = float(obj.to_moduli(np.asarray(theta, dtype=float).reshape(1, -1))[0, 0])
    resid = likelihood_residuals(obj, objective, curves, 1e-3 * noise.sd_um,
                                 MODEL_ERROR_RELATIVE if scale_free else 0.0,
                                 x1d if scale_free and correlated else None)
    params = {"X1d": lambda t: obj.to_moduli(t)[:, 0], "X1h": lambda t: obj.to_moduli(t)[:, 1]}
    try:
        ci = profile_intervals(resid, theta, obj.lower, obj.upper, params, level=level,
                               noise_dof=noise.dof, fit_is_minimum=objective == "single")
    except ValueError as err:
        warnings.append(f"no intervals: {err}")
        return noise.to_dict(), None
    for name, iv in ci.parameters.items():
        sides = [s for s, o in (("below", iv.lower_open), ("above", iv.upper_open)) if o]
        if sides:
            warnings.append(f"{name} is not bounded {' or '.join(sides)} by the data within the "
                            f"simulated space: its {100 * level:g} % interval "
                            f"{iv.text('MPa')} reaches the edge of the space")
    if ci.scale > 1.5:
        warnings.append(f"the residuals are {math.sqrt(ci.scale):.2g} times the noise: the "
                        "intervals are widened for the misfit (see skinsuction diagnose)")
    warnings.extend(ci.notes)
    return noise.to_dict(), ci.to_dict()


def thickness_uncertainty(setup: RampSetup, theta, est, intervals, level, noise=None):
    """Widen the intervals for the sd of the given thicknesses (Laplace approximation).

    For each thickness ``t`` given with an sd, the fit is polished again, from the
    estimate, on the rays of ``t - sd`` and ``t + sd``.  With ``c(t)``, the chi2 of
    the fit at ``t`` on the intervals' likelihood (the noise and the space's own
    error), the thickness is a nuisance parameter with the Gaussian prior
    ``(t - t0) / sd``: its posterior sd is ``1 / sqrt(1 / sd^2 + c''(t0) / 2)`` (the
    curves may pin it down better than the prior), not below the 0.01 mm the rays
    resolve, and the moduli move by ``d log X / dt`` (central difference) times it.
    The interval half-widths (in log) are combined with ``z`` times these moves in
    quadrature (``z`` the normal quantile of the level).

    Where the curves prefer another thickness (the vertex of that quadratic, within
    2 sd, located again along the move by :func:`_refined`; then, with a noise, the
    posterior's mode over the thickness lattice, :func:`._thickness_profile._at_mode`),
    the estimate is the fit there and the intervals are centred on it; they reach as
    far as the profile over the thicknesses takes them (:func:`_profiled`).  On the
    layers study's 200 ramps the X1d intervals held the truth in 62 % holding the given
    thicknesses, 94 % now (docs/geometry.md#thickness-uncertainty).

    Parameters
    ----------
    setup : RampSetup
    theta : array_like
        The estimate (the objective's coordinates).
    est : array_like
        The estimate (MPa).
    intervals : dict or None
        The intervals of :func:`noise_and_intervals`, widened in place.
    level : float
        Their confidence level.
    noise : dict, optional
        The noise of :func:`noise_and_intervals` (its ``sd_um``).

    Returns
    -------
    thickness : dict or None
        Per thickness: the sensitivities, the posterior sd, the thickness the
        curves prefer within the prior and the one the estimate is fitted at
        (``estimate_at_mm``); None without a sd.
    est : ndarray
        The estimate (MPa): ``est``, or the fit at the thicknesses the curves
        prefer.
    """

    space, geometry, probes, curves = setup.space, setup.geometry, setup.probes, setup.curves
    sds = {k: v for k, v in (geometry.sd or {}).items() if v and v > 0}
    if not sds or space.rays is None:
        return None, est
    sigma_mm = 1e-3 * float((noise or {}).get("sd_um") or 0.0)

    def fit_at(g, moved=None):
        moved = space.at(g) if moved is None else moved
        obj, th = _polish_near(setup, {p: moved.probe(p) for p in probes}, theta)
        # chi^2 on the moduli intervals' likelihood (the noise and the space's own error),
        # so that the thickness's posterior agrees with them; on the noise alone the
        # layers study's ramps held X1d in 83 %, on it 78 % (docs/studies.md)
        x1d = float(obj.to_moduli(th.reshape(1, -1))[0, 0]) if setup.scale_free else None
        resid = likelihood_residuals(obj, setup.objective, curves, max(sigma_mm, 1e-9),
                                     MODEL_ERROR_RELATIVE if setup.scale_free else 0.0, x1d)
        r = np.nan_to_num(np.asarray(resid(th.reshape(1, -1)), dtype=float).ravel())
        chi2 = float(r @ r)
        for n in moved.notes(probes):
            if n not in space.notes(probes) and n not in notes_seen:
                notes_seen.append(n)
        points.append((g, obj.to_moduli(th)[0], chi2))
        vectors.append(r)
        return obj.to_moduli(th)[0], chi2

    points = []  # (geometry, moduli, chi2) of every fit: the profile over the thicknesses
    vectors = []  # their residual vectors (chi2 = r @ r)

    notes_seen = []
    _, c0 = fit_at(geometry)
    out = {}
    for key, sd in sds.items():
        lo, c_lo = fit_at(geometry.shifted(key, -sd))
        hi, c_hi = fit_at(geometry.shifted(key, sd))
        name = {"t_d": "dermis_thickness", "t_h": "hypodermis_thickness"}[key]
        out[name] = _thickness_record(getattr(geometry, key), sd, (lo, hi), (c_lo, c0, c_hi),
                                      sigma_mm > 0)
    est0, (est, moves) = est, _at_preferred(setup, fit_at, out, est, c0)
    setup.warnings.extend(f"geometry (thickness +- 1 sd): {n}" for n in notes_seen)
    if intervals is not None:
        scale = float(intervals.get("misfit_scale") or 1.0)
        edge = _profile_fits(setup, fit_at, sds, points, scale)
        if sigma_mm > 0:
            q = float(intervals.get("delta_chi2_threshold") or 0.0) / scale
            est = _at_mode(setup, fit_at, sds, scale, q, (points, vectors), out, est, moves)
        profiled = _profiled(intervals, points, geometry, sds, est0)
        _widen(intervals, out, est0, est, level)
        _widen_to(intervals, profiled, edge)
    _note_moves(setup, out, moves)
    return out, est


#: Half-width (decades) of the X1d window of the tables a fit at another thickness
#: reads: the whole table spans 2.3 decades (a tenth of a second a probe), the polish
#: from the estimate moved X1d by 0.006 decades in the median, 0.08 at the 95th pct
#: and 0.20 at most (352 fits of 12 ramps of the layers study, 0.1 mm sd).
POLISH_WINDOW_DECADES = 0.3


def _polish_near(setup, spaces, theta):
    """The objective on ``spaces`` and its polish from ``theta``: on tables of the X1d
    window :data:`POLISH_WINDOW_DECADES` either side of it (the whole tables' values
    there, a quarter of their cost), and again on the whole tables if the polish read
    outside that window."""
    theta = np.asarray(theta, dtype=float)
    args = (setup.curves, setup.probes, setup.alpha, setup.data.path)
    if setup.scale_free and all(hasattr(s, "windowed") for s in spaces.values()):
        w = POLISH_WINDOW_DECADES
        near = {p: s.windowed(theta[0] - w, theta[0] + w) for p, s in spaces.items()}
        obj = make_objective(setup.objective, near, *args)
        th = polish(obj, theta)
        if not any(s.read_outside() for s in near.values()):
            return obj, th
    obj = make_objective(setup.objective, spaces, *args)
    return obj, polish(obj, theta)


def _thickness_record(t0, sd, moduli, chi2, with_noise: bool) -> dict:
    """One thickness's record from the fits at ``t0 -+ sd`` (``moduli``: their X1d, X1h)
    and the chi^2 at ``t0 - sd, t0, t0 + sd``: the quadratic through them and the prior."""
    lo, hi = moduli
    c_lo, c0, c_hi = chi2
    d = (np.log(hi) - np.log(lo)) / 2  # d log X per sd
    post_sd, preferred, g = sd, None, None
    if with_noise:
        k = max((c_hi - 2 * c0 + c_lo) / sd ** 2, 0.0)
        g = (c_hi - c_lo) / (2 * sd)
        # the rays resolve a thickness to 0.01 mm (the rays on demand round to it): a
        # posterior sd below that is the rounding's
        post_sd = max(1.0 / math.sqrt(1.0 / sd ** 2 + k / 2), THICKNESS_RESOLUTION_MM)
        preferred = t0 - g / (k + 2 / sd ** 2)
    return {"sd_mm": sd, "posterior_sd_mm": post_sd, "preferred_by_the_curves_mm": preferred,
            "chi2_slope_per_mm": None if g is None else float(g),
            "d_log_X1d_per_sd": float(d[0]), "d_log_X1h_per_sd": float(d[1]),
            "X1d_change_percent_per_sd": float(100 * np.expm1(d[0])),
            "X1h_change_percent_per_sd": float(100 * np.expm1(d[1])),
            "log_shift": [float(abs(d[0]) * post_sd / sd), float(abs(d[1]) * post_sd / sd)]}


def _widen(intervals, out, est0, est, level) -> None:
    """The intervals about ``est0``, centred on ``est`` and widened in log, in
    quadrature, by ``z`` times each thickness's move of the moduli (in place)."""
    from scipy import stats

    z = float(stats.norm.ppf(0.5 + level / 2))
    for i, name in enumerate(("X1d", "X1h")):
        iv = intervals.get(name)
        if not iv:
            continue
        g = math.sqrt(sum(v["log_shift"][i] ** 2 for v in out.values()))
        e0, e = float(est0[i]), float(est[i])
        for side, sign in (("lower", -1), ("upper", 1)):
            h = abs(math.log(iv[side] / e0)) if iv[side] and iv[side] > 0 else 0.0
            iv[side] = e * math.exp(sign * math.hypot(h, z * g))
        iv["includes_thickness_sd"] = True
    intervals["notes"] = list(intervals.get("notes", [])) + [
        "the intervals include the sd of the given thicknesses (Laplace approximation: "
        "the fit at each thickness +- 1 sd, a Gaussian prior on the thickness)"]


#: The farthest a thickness the curves prefer moves the estimate, in sd of the given one
#: (the quadratic through the fits at +- 1 sd that locates it is an extrapolation beyond).
MAX_MOVE_SD = 2.0


def _at_preferred(setup, fit_at, out, est, c0):
    """The estimate refitted at the thicknesses the curves prefer (``out`` records them),
    and how each moved (``{key: remark}``, for :func:`_note_moves`); ``est`` where they
    prefer the given ones (within a tenth of the posterior sd).

    The vertex of the quadratic through the fits at +- 1 sd overshoots where chi^2 is
    far from quadratic (a 0.60 mm dermis given as 0.70 came out at 0.56): along the
    move, the parabola through the posterior at the given thicknesses, its slope
    there and its value at the vertex locates the mode again, and the fit there is
    taken if the posterior is higher (one fit more)."""
    geometry, moved, move, remarks = setup.geometry, setup.geometry, {}, {}
    for key, name in (("t_d", "dermis_thickness"), ("t_h", "hypodermis_thickness")):
        rec = out.get(name)
        if rec is None:
            continue
        t0, sd, pref = getattr(geometry, key), rec["sd_mm"], rec["preferred_by_the_curves_mm"]
        rec["estimate_at_mm"] = t0
        if pref is None or abs(pref - t0) <= 0.1 * rec["posterior_sd_mm"]:
            continue
        t = float(np.clip(pref, t0 - MAX_MOVE_SD * sd, t0 + MAX_MOVE_SD * sd))
        moved, rec["estimate_at_mm"] = moved.shifted(key, t - t0), t
        move[key] = (name, t - t0)
    if moved is geometry:
        return est, remarks
    at, c1 = fit_at(moved)
    at, s = _refined(setup, fit_at, out, move, at, c0, c1)
    for key, (name, delta) in move.items():
        rec, t0 = out[name], getattr(geometry, key)
        t, pref, sd = t0 + s * delta, rec["preferred_by_the_curves_mm"], rec["sd_mm"]
        rec["estimate_at_mm"] = t
        remarks[key] = ((f"; the quadratic through ±1 sd puts it at {pref:.3g}" if s != 1
                         and abs(t - pref) > 0.1 * rec["posterior_sd_mm"] else "")
                        + (f"; at most {MAX_MOVE_SD:g} sd" if abs(t - t0) >= MAX_MOVE_SD * sd
                           - 1e-12 else ""))
    return np.asarray(at, dtype=float), remarks


def _note_moves(setup, out, remarks) -> None:
    """The warning that the estimate is the fit at other thicknesses than the given."""
    notes = []
    for key, name in (("t_d", "dermis_thickness"), ("t_h", "hypodermis_thickness")):
        rec = out.get(name)
        if rec is None or key not in remarks:
            continue
        t0 = getattr(setup.geometry, key)
        notes.append(f"{name.replace('_', ' ')} {rec['estimate_at_mm']:.3g} mm (given {t0:g} "
                     f"± {rec['sd_mm']:g}{remarks[key]})")
    if notes:
        setup.warnings.append("geometry: the curves prefer other thicknesses than the given "
                              "ones; the estimate is the fit at " + ", ".join(notes) +
                              ", the intervals about it")


def _refined(setup, fit_at, out, move, at, c0, c1):
    """The fit at the posterior's mode along the move (s = 1 at the quadratic's vertex):
    ``(estimate, s)``."""
    geometry = setup.geometry
    prior = {k: out[n]["sd_mm"] for k, (n, _) in move.items()}
    slope = sum(0.5 * (out[n]["chi2_slope_per_mm"] or 0.0) * d for n, d in move.values())

    def posterior(c, s):  # -log posterior (+ const) at s along the move
        return 0.5 * c + 0.5 * sum((s * d / prior[k]) ** 2 for k, (_, d) in move.items())

    f0, f1 = 0.5 * c0, posterior(c1, 1.0)
    a = f1 - f0 - slope
    if not (a > 0 and slope < 0 and math.isfinite(f1)):
        return at, 1.0
    s_max = min(MAX_MOVE_SD * prior[k] / abs(d) for k, (_, d) in move.items())
    s = float(np.clip(-slope / (2 * a), 0.0, max(s_max, 1.0)))
    if max(abs(s - 1) * abs(d) for _, d in move.values()) < THICKNESS_RESOLUTION_MM:
        return at, 1.0
    g = geometry
    for k, (_, d) in move.items():
        g = g.shifted(k, s * d)
    at_s, c_s = fit_at(g)
    return (at_s, s) if posterior(c_s, s) < f1 else (at, 1.0)
