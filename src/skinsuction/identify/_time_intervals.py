"""Intervals of a time fit: the Laplace approximation under a correlated model error.

:func:`laplace_intervals`: the Gauss-Newton (Laplace) approximation in theta (logs),
``theta_i +- sqrt(q s C_ii)`` with C the covariance of the weighted least-squares
estimate, q the chi^2(1) quantile and s the Birge ratio where the residuals exceed
the noise significantly (:func:`skinsuction.identify.misfit_scale`, as the profile
intervals).  A profile scan in 4-6 dimensions over curves of thousands of samples
costs minutes per curve; the Laplace interval is checked for coverage on FE virtual
experiments (``benchmarks/time_identify.py``).  An interval that crosses a bound of
the space or of the spectrum is cut there and marked open.

The model error of the fast path is smooth along a curve, not independent between
points: C is the sandwich ``H^-1 J^T (D + B B^T) J H^-1`` with B the systematic
terms of each curve (:func:`systematic_basis`: Legendre polynomials per phase, the
space's accuracy, the rounding's sawtooth) and D the independent noise.
:func:`time_bound_flags` says which parameters sit at an edge.
"""

from __future__ import annotations

import math

import numpy as np

from ._bounds import bound_flags
from ._likelihood import central_jacobian, interval_threshold, misfit_scale
from ._time_fit import MODEL_ERROR, TimeCurveModel, TimeFit, TimeFitData, TimeObjective

__all__ = ["SYSTEMATIC_DEGREE", "ROUNDING_HARMONICS", "decorrelate_low_rank",
           "laplace_intervals", "rounding_terms", "sandwich_covariance", "systematic_basis",
           "time_bound_flags", "whitened_systematic"]


#: The model error is systematic (smooth along the curve), not independent between
#: points: in the intervals it is one smooth function per curve and phase, spanned by
#: the Legendre polynomials of degree 0..SYSTEMATIC_DEGREE in time over each segment
#: of that phase (the same coefficients in every cycle: the protocol repeats), each
#: of variance (f_phase U)^2 / (degree + 1); the space's accuracy (0.002 M) is one
#: term along the whole curve, as the ramps' space error (``space_error_direction``).
SYSTEMATIC_DEGREE = 2

#: Harmonics of the rounding's systematic part (see :func:`rounding_terms`).
ROUNDING_HARMONICS = 3


def _segments(phase, name):
    """[(start, stop)] of the runs of ``phase == name``."""
    sel = np.concatenate([[False], phase == name, [False]]).astype(int)
    edges = np.flatnonzero(np.diff(sel))
    return list(zip(edges[0::2], edges[1::2]))


def rounding_terms(data: TimeFitData, fitted_mm, harmonics: int = ROUNDING_HARMONICS):
    """``(columns (n, 2 K), variance)`` of the rounding's systematic part at the
    deflections ``fitted_mm`` (all points of the curve).

    A deflection x read to a step q with Gaussian noise s before the rounding is off
    on average by ``b(x) = sum_k (-1)^k q / (pi k) exp(-2 pi^2 k^2 s^2 / q^2)
    sin(2 pi k x / q)``: a function of the level, so the same over a hold or a slow
    creep (correlated), not averaged away by many samples.  With the level's phase on
    the grid unknown, ``Cov(b(x_i), b(x_j)) = sum_k a_k^2 / 2 cos(2 pi k (x_i - x_j) / q)``:
    two columns (cos, sin) per harmonic.  s is the noise beyond the rounding's
    q^2 / 12 (0 when the curve shows no more: the whole sawtooth is then systematic).

    Parameters
    ----------
    data : TimeFitData
        The curve (its ``resolution_mm`` q and ``noise_sd_mm``).
    fitted_mm : array_like (n,)
        The fitted deflections at every point.
    harmonics : int
        K, harmonics of the sawtooth.

    Returns
    -------
    columns : ndarray (n, 2 K)
        In mm; no columns without a rounding step.
    variance : float
        Their summed variance (mm^2).
    """
    q = float(data.resolution_mm or 0.0)
    if q <= 0 or harmonics < 1:
        return np.zeros((len(data.time_s), 0)), 0.0
    s2 = max(data.noise_sd_mm ** 2 - q ** 2 / 12.0, 0.0)
    x = np.nan_to_num(np.asarray(fitted_mm, dtype=float))
    cols, var = [], 0.0
    for k in range(1, harmonics + 1):
        a = q / (math.pi * k) * math.exp(-2.0 * math.pi ** 2 * k ** 2 * s2 / q ** 2)
        w = 2.0 * math.pi * k * x / q
        cols += [a / math.sqrt(2.0) * np.cos(w), a / math.sqrt(2.0) * np.sin(w)]
        var += a ** 2 / 2.0
    return np.column_stack(cols), var


def systematic_basis(data: TimeFitData, degree: int = SYSTEMATIC_DEGREE, fitted_mm=None):
    """``(B, D)`` of one curve's used points: the systematic covariance ``B B^T`` (B in
    mm, one column per phase and Legendre degree, and one for the space's accuracy)
    and the independent variance ``D`` (mm^2: the noise and the 0.3 µm floor).

    Over a segment the mean of each column's square is (f_phase U)^2 / (degree + 1)
    (each polynomial scaled to a mean square of 1 over the segment's points):
    ``diag(B B^T) + D`` equals the fit's sd^2 on average over each segment.

    Parameters
    ----------
    data : TimeFitData
    degree : int
        Highest Legendre degree per phase.
    fitted_mm : array_like (n,), optional
        The fitted curve: the rounding's systematic part is added
        (:func:`rounding_terms`) and taken from the noise.

    Returns
    -------
    B : ndarray (used points, columns)
    D : ndarray (used points,)
    """
    from .measured_fit import MODEL_ERROR_MM, MODEL_ERROR_RELATIVE

    fractions = {**MODEL_ERROR, **(data.model_error or {})}
    t, ph = np.asarray(data.time_s, dtype=float), np.asarray(data.phase)
    cols = []
    for name in dict.fromkeys(ph):
        f = float(fractions.get(name, 0.0))
        if f <= 0:
            continue
        segs = _segments(ph, name)
        for j in range(degree + 1):
            c = np.zeros(t.size)
            for a, b in segs:
                x = (np.zeros(b - a) if b - a < 2 else
                     2.0 * (t[a:b] - t[a]) / (t[b - 1] - t[a]) - 1.0)
                v = np.polynomial.legendre.legval(x, np.eye(degree + 1)[j])
                ms = float(np.mean(v ** 2))
                c[a:b] = v / math.sqrt(ms) if ms > 0 else 0.0  # mean square 1 on the segment
            cols.append(c * f * data.scale_mm / math.sqrt(degree + 1))
    cols.append(MODEL_ERROR_RELATIVE * np.abs(np.asarray(data.deflection_mm, dtype=float)))
    noise2 = data.noise_sd_mm ** 2
    if fitted_mm is not None:
        rc, rvar = rounding_terms(data, fitted_mm)
        cols += list(rc.T)
        # a floor: with the rounding taking all of the noise, a point at rest (no model
        # error there) would get no independent variance and break the decorrelation
        noise2 = max(noise2 - rvar, 0.01 * data.noise_sd_mm ** 2)
    B = np.column_stack(cols)[data.used]
    D = (noise2 + MODEL_ERROR_MM ** 2 * (ph != "rest"))[data.used]
    return B, D


def whitened_systematic(data: list, degree: int = SYSTEMATIC_DEGREE, fitted_mm=None):
    """``(Bw, Dw)`` of all curves, whitened by the fit's sd (the rows of
    :meth:`TimeObjective.whitened`): Bw block-diagonal over the curves; with the
    fitted curves, the rounding's systematic part too (:func:`rounding_terms`).

    Parameters
    ----------
    data : list of TimeFitData
    degree : int
        Highest Legendre degree per phase.
    fitted_mm : list of array_like, optional
        Each curve's fitted deflections.

    Returns
    -------
    Bw : ndarray (n, columns)
    Dw : ndarray (n,)
    """
    fitted_mm = fitted_mm if fitted_mm is not None else [None] * len(data)
    blocks = [systematic_basis(d, degree, f) for d, f in zip(data, fitted_mm)]
    k = sum(b.shape[1] for b, _ in blocks)
    Bw, Dw, col = [], [], 0
    for d, (b, dd) in zip(data, blocks):
        sd = d.sd_mm[d.used]
        m = np.zeros((b.shape[0], k))
        m[:, col:col + b.shape[1]] = b / sd[:, None]
        col += b.shape[1]
        Bw.append(m)
        Dw.append(dd / sd ** 2)
    return np.vstack(Bw), np.concatenate(Dw)


def decorrelate_low_rank(z, Bw, Dw):
    """Residuals ``z`` (N, n) whitened by the fit's sd, decorrelated under the
    covariance ``diag(Dw) + Bw Bw^T`` (in those units): the squared norm of each row
    is ``z^T (diag(Dw) + Bw Bw^T)^-1 z`` (Woodbury through a thin SVD of
    ``diag(Dw)^-1/2 Bw``; rank one: :func:`.measured_fit.decorrelate`).

    Parameters
    ----------
    z : array_like (N, n) or (n,)
    Bw : ndarray (n, columns)
    Dw : ndarray (n,)
        As :func:`whitened_systematic` gives them.

    Returns
    -------
    ndarray (N, n)
    """
    z = np.atleast_2d(z) / np.sqrt(Dw)[None, :]
    U, sv, _ = np.linalg.svd(Bw / np.sqrt(Dw)[:, None], full_matrices=False)
    shrink = 1.0 - 1.0 / np.sqrt(1.0 + sv ** 2)
    return z - np.einsum("nk,tk->nt", np.einsum("nt,tk->nk", z, U) * shrink, U)


def sandwich_covariance(J, Bw, Dw):
    """Covariance of the weighted least-squares estimate when the errors are
    correlated: ``H^-1 J^T (diag(Dw) + Bw Bw^T) J H^-1``, H = J^T J, J the Jacobian
    of the residuals whitened by the fit's sd.

    Parameters
    ----------
    J : ndarray (n, d)
    Bw : ndarray (n, columns)
    Dw : ndarray (n,)

    Returns
    -------
    ndarray (d, d)
    """
    Hinv = np.linalg.pinv(J.T @ J)
    JB = J.T @ Bw
    meat = (J * Dw[:, None]).T @ J + JB @ JB.T
    return Hinv @ meat @ Hinv


def _log_forms(theta, terms: int, k0: int = 2) -> dict:
    """Each reported quantity as a linear form of theta in log10 (exact in the logs;
    the instantaneous moduli by the derivative of log10(1 + sum g) at the fit).
    ``k0``: where the spectrum starts in theta."""
    d = theta.size
    forms = {"X1d": np.eye(d)[0], "X1h": np.eye(d)[0] + np.eye(d)[1]}
    order = np.argsort(theta[k0 + 1::2]) if terms else []
    for k, j in enumerate(order, start=1):
        forms[f"g_{k}"] = np.eye(d)[k0 + 2 * j]
        forms[f"tau_{k}"] = np.eye(d)[k0 + 1 + 2 * j]
    if terms:
        g = 10.0 ** theta[k0::2]
        dlog = np.zeros(d)
        dlog[k0::2] = g / (1.0 + g.sum())
        forms["X1d_instantaneous"] = forms["X1d"] + dlog
        forms["X1h_instantaneous"] = forms["X1h"] + dlog
    return forms


def _layer_forms(theta, k0: int) -> dict:
    """The forms of a fit with a spectrum per layer (one term each)."""
    e = np.eye(theta.size)
    return {"X1d": e[0], "X1h": e[0] + e[1], "g_dermis": e[k0], "tau_dermis": e[k0 + 1],
            "g_hypodermis": e[k0 + 2], "tau_hypodermis": e[k0 + 3]}


def _form_interval(name, a, theta, cov, q, lo, hi, ok, k0: int = 2) -> dict:
    """The interval of one form: centre +- sqrt(q a^T C a), cut at the box (open there)."""
    centre = float(a @ theta) if not name.endswith("instantaneous") else \
        float(a[:2] @ theta[:2] + math.log10(1.0 + (10.0 ** theta[k0::2]).sum()))
    half = math.sqrt(max(float(a @ cov @ a), 0.0) * q)
    lower, upper = centre - half, centre + half
    # cut at the box of the space and the spectrum (the form's range over it)
    b_lo = float(np.sum(np.minimum(a * lo, a * hi)))
    b_hi = float(np.sum(np.maximum(a * lo, a * hi)))
    if name.endswith("instantaneous"):
        b_lo, b_hi = b_lo + centre - float(a @ theta), b_hi + centre - float(a @ theta)
    lo_open, up_open = bool(lower <= b_lo), bool(upper >= b_hi)
    lower, upper = max(lower, b_lo), min(upper, b_hi)
    if not ok[np.flatnonzero(a)].all():
        lo_open = up_open = True
    return {"estimate": 10.0 ** centre, "lower": 10.0 ** lower, "upper": 10.0 ** upper,
            "lower_open": lo_open, "upper_open": up_open}


def _cause_interval(model, theta, cov, q, ok) -> dict:
    """The interval of the cause's parameter (e.g. X2d, MPa): linear in its value
    (it may be the neutral 0), the gradient over theta by central differences,
    cut at the space's range of the axis coordinate (open there)."""
    def value(t):
        return model.cause_value(t)

    k = 2  # the axis coordinate
    grad = np.zeros(theta.size)
    for i in (0, k):
        h = 1e-5 * max(model.upper[i] - model.lower[i], 1e-12)
        tp, tm = theta.copy(), theta.copy()
        tp[i], tm[i] = min(theta[i] + h, model.upper[i]), max(theta[i] - h, model.lower[i])
        grad[i] = (value(tp) - value(tm)) / (tp[i] - tm[i])
    centre = value(theta)
    half = math.sqrt(max(float(grad @ cov @ grad), 0.0) * q)
    edge_lo = value(np.concatenate([theta[:k], [model.lower[k]], theta[k + 1:]]))
    edge_hi = value(np.concatenate([theta[:k], [model.upper[k]], theta[k + 1:]]))
    lower, upper = centre - half, centre + half
    lo_open, up_open = bool(lower <= edge_lo), bool(upper >= edge_hi)
    if not ok[[0, k]].all():
        lo_open = up_open = True
    return {"estimate": centre, "lower": max(lower, edge_lo), "upper": min(upper, edge_hi),
            "lower_open": lo_open, "upper_open": up_open,
            "scale": "linear in the value; its ends are the space's range of "
                     f"{model.cause.name} at the fitted X1d"}


def _form_correlations(forms: dict, cov) -> dict:
    """The correlation of every pair of forms (the instantaneous moduli left out)."""
    names = [k for k in forms if not k.endswith("instantaneous")]
    corr = {}
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            va, vb = forms[a], forms[b]
            den = math.sqrt(max(va @ cov @ va, 0) * max(vb @ cov @ vb, 0))
            corr[f"{a},{b}"] = float(va @ cov @ vb / den) if den > 0 else None
    return corr


def laplace_intervals(rays: dict, data: list, fit: TimeFit, *, level: float = 0.95,
                      step: float = 1e-4, correlated: bool = True) -> dict:
    """Gauss-Newton (Laplace) intervals of every parameter of ``fit``.

    In theta (logs): ``theta_i +- sqrt(q s C_ii)``, C = (J^T J)^-1 (or the sandwich
    under the correlated model error) from central differences (``step`` in log10
    units), q the chi^2(1) quantile of ``level``, s the Birge ratio if the misfit is
    significant (else 1).  X1h and the instantaneous moduli are linear in theta's
    logs: their log-sd is g^T C g.  An end beyond a bound of the space or of the
    spectrum is cut there and open.

    Parameters
    ----------
    rays : dict
        Probe (mm) -> neo-Hookean RaySpace, as fitted.
    data : list of TimeFitData
        The fitted curves.
    fit : TimeFit
        The fit (:func:`skinsuction.identify.fit_time_model`).
    level : float
        Confidence level of each interval.
    step : float
        Central-difference step in log10 units.
    correlated : bool
        The model error as a correlated term (sandwich covariance); False:
        independent points.

    Returns
    -------
    dict
        JSON-able, the shape of :meth:`LikelihoodIntervals.to_dict`.
    """
    model = TimeCurveModel(rays, data, fit.terms, getattr(fit, "layers", False))
    obj = TimeObjective(model)
    theta = np.asarray(fit.theta, dtype=float)
    d, n = theta.size, obj.n
    lo, hi = model.lower, model.upper
    J = central_jacobian(obj.whitened, theta, step, lo, hi)  # (n, d)
    notes = []
    ok = np.all(np.isfinite(J), axis=0)
    J = np.where(np.isfinite(J), J, 0.0)
    Bw, Dw = whitened_systematic(model.data, fitted_mm=fit.fitted_mm)
    cov = sandwich_covariance(J, Bw, Dw) if correlated else np.linalg.pinv(J.T @ J)
    r0 = obj.whitened(theta[None, :])
    chi2_corr = float(np.sum(decorrelate_low_rank(np.where(np.isfinite(r0), r0, 0.0),
                                                  Bw, Dw) ** 2))
    if not ok.all():
        notes.append("some parameters sit where a step leaves the space: their intervals "
                     "are open on that side")
    scale = misfit_scale(fit.chi2, max(n - d, 1))
    q = interval_threshold(level) * scale
    forms = (_layer_forms(theta, model.k0) if model.layers
             else _log_forms(theta, fit.terms, model.k0))
    out = {name: _form_interval(name, a, theta, cov, q, lo, hi, ok, model.k0)
           for name, a in forms.items()}
    if model.cause is not None:
        out[model.cause.symbol] = _cause_interval(model, theta, cov, q, ok)
    sd = np.sqrt(np.maximum(np.diag(cov), 0.0))
    method = ("Gauss-Newton (Laplace) approximation in log10 of each parameter, the "
              "covariance of the weighted least-squares estimate under a correlated model "
              "error (sandwich: Legendre terms per curve and phase, the space's accuracy "
              "along each curve), coverage measured by benchmarks/time_identify.py"
              if correlated else "Gauss-Newton (Laplace) approximation in log10 of each "
              "parameter, independent points, coverage measured by "
              "benchmarks/time_identify.py")
    return {"method": method,
            "level": float(level), **out, "correlation": _form_correlations(forms, cov),
            "chi2_min": float(fit.chi2),
            "delta_chi2_threshold": float(q), "misfit_scale": float(scale),
            "noise_dof": None, "n_points": int(n), "sd_log10": sd.tolist(),
            "correlated_model_error": bool(correlated), "chi2_correlated": chi2_corr,
            "systematic_terms": int(Bw.shape[1]),
            "notes": notes}


def time_bound_flags(rays: dict, data: list, fit: TimeFit, config_keys=None) -> dict:
    """``{parameter: flag}``: which fitted coordinates sit at an edge of the space (X1d,
    X1h/X1d: window or coverage) or of the spectrum's bounds (g_i, tau_i).

    Parameters
    ----------
    rays : dict
        Probe (mm) -> neo-Hookean RaySpace, as fitted.
    data : list of TimeFitData
        The fitted curves.
    fit : TimeFit
    config_keys : list of (str, str), optional
        The configuration keys that widen the space at the lower and upper edge of
        each parameter (the spectrum's are named by default).

    Returns
    -------
    dict
        The flags of :func:`skinsuction.identify.bound_flags` by parameter, each with
        ``neutral`` (a cause at its neutral end: the model without it) and ``flat``
        (a modulus at a window edge that the curves do not hold there:
        :data:`FLAT_DECADES`, :data:`FLAT_DELTA_CHI2`).
    """
    model = TimeCurveModel(rays, data, fit.terms, getattr(fit, "layers", False))
    obj = TimeObjective(model)
    theta = np.asarray(fit.theta, dtype=float)
    cause = [] if model.cause is None else [model.cause.symbol]
    spectrum = ([f"{k}_{i}" for i in range(1, fit.terms + 1) for k in ("g", "tau")]
                if not model.layers else
                ["g_dermis", "tau_dermis", "g_hypodermis", "tau_hypodermis"])
    names = ["X1d", "X1h"] + cause + spectrum
    kinds = ["log", "log"] + ["axis"] * (len(cause) + len(spectrum))
    keys = list(config_keys or [(None, None)] * 2)[:2]
    if cause:
        keys.append((f"scale_free_space.causes.{model.cause.name}.nodes",) * 2)
    keys = list(keys) + [(f"the spectrum's bounds (g {_bounds_text('g')}, tau "
                          f"{_bounds_text('tau')} s)",) * 2] * (len(names) - len(keys))
    flags = bound_flags(obj, theta, names, kinds, keys)
    with np.errstate(all="ignore"):
        cost = float(obj(theta[None, :])[0])
    for i, f in enumerate(flags):
        f["neutral"] = False
        f["flat"] = bool(f["edge"] == "window" and kinds[i] == "log"
                         and _flat_inward(obj, theta, i, f["side"], cost))
    if cause:
        # a cause at its neutral end (e.g. X2d = 0) is the model without it, not an edge
        f, c = flags[2], model.cause
        end = c.nodes[0] if f["side"] == "lower" else c.nodes[-1]
        f["neutral"] = bool(f["edge"] == "window" and end == c.neutral)
    return {f["parameter"]: f for f in flags}


#: A modulus at an edge of the window is ``flat`` there when moving it this many
#: decades inward, all else held, changes chi^2 by less than :data:`FLAT_DELTA_CHI2`:
#: the curves do not hold it at the edge (a 2 mm probe over a thick dermis cannot tell
#: X1h/X1d = 1e-4 from 1e-3), and with the others re-fitted the change is smaller still.
FLAT_DECADES, FLAT_DELTA_CHI2 = 1.0, 1.0


def _flat_inward(obj, theta, i, side, cost) -> bool:
    """Whether chi^2 changes by less than FLAT_DELTA_CHI2 a decade inward of the edge."""
    t = np.array(theta, dtype=float)
    t[i] += FLAT_DECADES if side == "lower" else -FLAT_DECADES
    t[i] = min(max(t[i], obj.lower[i]), obj.upper[i])
    with np.errstate(all="ignore"):
        inward = float(obj(t[None, :])[0])
    return bool(np.isfinite(inward) and 2.0 * (inward - cost) < FLAT_DELTA_CHI2)


def _bounds_text(kind):
    from ._time_model import G_BOUNDS, TAU_BOUNDS_S

    lo, hi = G_BOUNDS if kind == "g" else TAU_BOUNDS_S
    return f"{lo:g}-{hi:g}"
