"""Fit the elastic (g = 0) or viscoelastic model to time curves: the core.

:func:`fit_time_model` fits ``theta = (log10 X1d, log10 X1h/X1d[, log10 g_i,
log10 tau_i ...])`` (0, 1 or 2 Prony terms, one spectrum for both layers) to one
or more time curves (:class:`TimeFitData`, e.g. two probes of one skin) with the
fast path on the scale-free space (:mod:`._time_model`), in the project's way:
window focusing in the box of the space and the spectrum's bounds (paper
section 2.4), the best runs polished by bounded least squares.  It returns
chi^2, the residuals and chi^2 of every phase, and the parameters
(:class:`TimeFit`), so a diagnosis can compare the elastic and the viscoelastic
fits of one curve.

The likelihood
--------------
Gaussian, independent points, the sd of a point

    sd^2 = sigma^2 + (f_phase U)^2 + (0.002 M)^2 + (0.3 µm)^2,

``sigma`` the loader's noise sd (never below the 0.01 mm quantisation's
q/sqrt(12)), ``M`` the measured deflection with the space's accuracy target as for
ramps, ``U`` the curve's largest deflection and ``f_phase`` the fast path's
measured error against FE time solves in that phase (:data:`MODEL_ERROR`,
``docs/viscoelasticity.md``: within 0.34 % of Uf while the suction is on, up to
2.3 % in the 0.1 s after a release and 1.3 % in the off time).  ``phases="on"``
fits only while the suction is on (the alternative; see
``docs/time_identification.md`` for the two compared).

Intervals
---------
:func:`laplace_intervals`: the Gauss-Newton (Laplace) approximation in theta (logs),
``theta_i +- sqrt(q s C_ii)`` with C the inverse of J^T J of the whitened residuals,
q the chi^2(1) quantile and s the Birge ratio where the residuals exceed the noise
significantly (as :func:`skinsuction.identify.profile_intervals`).  A profile
scan in 4-6 dimensions over curves of thousands of samples costs minutes per
curve; the Laplace interval is checked for coverage on FE virtual experiments
(``benchmarks/time_identify.py``).  An interval that crosses a bound of the space
or of the spectrum is cut there and marked open.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import stats
from scipy.optimize import least_squares

from ._bounds import bound_flags
from ._intervals import interval_threshold
from ._time_model import (
    ElasticRays,
    clean_pressure,
    effective_pressures,
    pressure_breaks,
    prony_of,
    sort_terms,
    spectrum_bounds,
    theta_names,
)
from ._window_focusing import IdentificationError, window_focusing

__all__ = ["MODEL_ERROR", "SYSTEMATIC_DEGREE", "TIME_WF", "TimeFitData", "TimeFit",
           "TimeCurveModel", "decorrelate_low_rank", "fit_data_of", "fit_time_model",
           "laplace_intervals", "sandwich_covariance", "systematic_basis", "time_bound_flags",
           "whitened_systematic"]

#: The fast path's model error as an sd, fraction of the curve's largest deflection,
#: per phase: "on" (suction on), "release" (the first 0.1 s after a step's release),
#: "off" (the rest of its off time), "ramp" (every phase of a ramp cycle, mode 2),
#: "rest" (before the first suction: no load, no error).  Between the median draw's
#: RMS and the worst draw's largest error of the fast-path benchmark
#: (docs/viscoelasticity.md: on 0.02-0.03 % / 0.34 %; release 0.68 % / 2.27 %;
#: off 0.22 % / 1.34 %; mode 2 0.03 % / 0.16 %).
MODEL_ERROR = {"on": 0.001, "release": 0.01, "off": 0.004, "ramp": 0.001, "rest": 0.0}

#: Seconds after a step's release counted as "release" (where Ur is read).
RELEASE_S = 0.1

#: Window focusing of the time fits: the paper's N and Nb, a looser stop (in units
#: of sqrt(chi^2 / n)) and fewer iterations: the polish finishes the job.
TIME_WF = {"n_samples": 1000, "n_best": 20, "tolerance": 1e-4, "max_iter": 60}


@dataclass(frozen=True)
class TimeFitData:
    """One time curve as fitted: the cleaned suction, the deflections, the sd of each
    point and its phase (``rest``, ``on``, ``release``, ``off``, ``ramp``)."""

    label: str
    probe_mm: float
    time_s: np.ndarray
    pressure_mbar: np.ndarray
    deflection_mm: np.ndarray
    sd_mm: np.ndarray
    phase: np.ndarray
    noise_sd_mm: float
    scale_mm: float
    used: np.ndarray  # bool: the point is in the likelihood
    breaks: np.ndarray = field(default=None)
    notes: tuple = ()
    model_error: dict = field(default=None)  # the fractions per phase (MODEL_ERROR if None)
    resolution_mm: float = 0.0  # the deflection's rounding step (0: none)

    @property
    def n(self) -> int:
        return int(self.used.sum())


def _phases(curve) -> np.ndarray:
    t = np.asarray(curve.time_s, dtype=float)
    out = np.full(t.size, "rest", dtype=object)
    for c in curve.cycles:
        stop = c.end + 1
        if c.kind == "ramp":
            out[c.onset:stop] = "ramp"
            continue
        out[c.onset:c.release] = "on"
        rel_end = c.release + int(np.searchsorted(t[c.release:stop], t[c.release] + RELEASE_S,
                                                  side="right"))
        out[c.release:rel_end] = "release"
        out[rel_end:stop] = "off"
    return out


def fit_data_of(curve, *, noise_sd_mm: float | None = None, model_error: dict | None = None,
                phases: str = "all") -> TimeFitData:
    """The :class:`TimeFitData` of a loaded :class:`skinsuction.measured.TimeCurve`.

    Parameters
    ----------
    curve : TimeCurve
    noise_sd_mm : float, optional
        Overrides the loader's noise estimate.
    model_error : dict, optional
        Fractions per phase (default :data:`MODEL_ERROR`); ``{}``-like zeros for none.
    phases : {"all", "on"}
        ``"on"``: only the points while the suction is on (and before it) are fitted.
    """
    if phases not in ("all", "on"):
        raise ValueError(f"phases must be 'all' or 'on', not {phases!r}")
    fractions = {**MODEL_ERROR, **(model_error or {})}
    p, note = clean_pressure(curve)
    d = np.asarray(curve.deflection_mm, dtype=float)
    phase = _phases(curve)
    sigma = float(curve.noise_sd_mm if noise_sd_mm is None else noise_sd_mm)
    if not sigma > 0:
        raise ValueError(f"{curve.label}: the noise sd must be positive (the curve shows "
                         "none: give it, --noise-um)")
    scale = float(np.percentile(np.abs(d), 99.5))
    f = np.array([fractions[k] for k in phase], dtype=float)
    # the space's own accuracy target (0.2 % of M and 0.3 µm), as for pressure ramps
    from .measured_fit import MODEL_ERROR_MM, MODEL_ERROR_RELATIVE

    sd = np.sqrt(sigma ** 2 + (f * scale) ** 2 + (MODEL_ERROR_RELATIVE * d) ** 2
                 + MODEL_ERROR_MM ** 2 * (phase != "rest"))
    used = np.ones(d.size, bool) if phases == "all" else np.isin(phase, ["rest", "on", "ramp"])
    t = np.asarray(curve.time_s, dtype=float)
    return TimeFitData(curve.label, float(curve.probe_mm), t, p, d, sd, phase, sigma, scale,
                       used, pressure_breaks(t, p), (note,), fractions,
                       float(getattr(curve, "resolution_mm", None) or _grid_step(d)))


def _grid_step(d) -> float:
    """The grid the deflections lie on, 0 if none: the loader's rule without its
    20-step range (that misses a small curve, 0.08 mm at 0.01 mm under a 2 mm probe)."""
    from skinsuction.measured._timecurve import grid_step

    return grid_step(d, min_steps=2) or 0.0


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
        noise2 = max(noise2 - rvar, 0.0)
    B = np.column_stack(cols)[data.used]
    D = (noise2 + MODEL_ERROR_MM ** 2 * (ph != "rest"))[data.used]
    return B, D


def whitened_systematic(data: list, degree: int = SYSTEMATIC_DEGREE, fitted_mm=None):
    """``(Bw, Dw)`` of all curves, whitened by the fit's sd (the rows of
    :meth:`_Objective.whitened`): Bw block-diagonal over the curves; with the
    fitted curves, the rounding's systematic part too (:func:`rounding_terms`)."""
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
    ``diag(Dw)^-1/2 Bw``; rank one: :func:`.measured_fit.decorrelate`)."""
    z = np.atleast_2d(z) / np.sqrt(Dw)[None, :]
    U, sv, _ = np.linalg.svd(Bw / np.sqrt(Dw)[:, None], full_matrices=False)
    shrink = 1.0 - 1.0 / np.sqrt(1.0 + sv ** 2)
    return z - np.einsum("nk,tk->nt", np.einsum("nt,tk->nk", z, U) * shrink, U)


def sandwich_covariance(J, Bw, Dw):
    """Covariance of the weighted least-squares estimate when the errors are
    correlated: ``H^-1 J^T (diag(Dw) + Bw Bw^T) J H^-1``, H = J^T J, J the Jacobian
    of the residuals whitened by the fit's sd."""
    Hinv = np.linalg.pinv(J.T @ J)
    JB = J.T @ Bw
    meat = (J * Dw[:, None]).T @ J + JB @ JB.T
    return Hinv @ meat @ Hinv


class TimeCurveModel:
    """Deflections of candidates theta on every fitted curve (the fast path).

    ``rays`` maps probe (mm) to its neo-Hookean :class:`~skinsuction.space.RaySpace`
    (``LoadedSpace.probe(p).space``); ``terms`` Prony terms (0: elastic).
    """

    def __init__(self, rays: dict, data: list, terms: int):
        if terms not in (0, 1, 2):
            raise ValueError(f"0, 1 or 2 Prony terms, not {terms}")
        self.data, self.terms = list(data), int(terms)
        self.elastic = {}
        for p in sorted({d.probe_mm for d in self.data}):
            p_max = max(float(d.pressure_mbar.max()) for d in self.data if d.probe_mm == p)
            self.elastic[p] = ElasticRays(rays[p], p, p_max)
        lo = np.max([e.lower for e in self.elastic.values()], axis=0)
        hi = np.min([e.upper for e in self.elastic.values()], axis=0)
        s_lo, s_hi = spectrum_bounds(self.terms)
        self.lower = np.concatenate([lo, s_lo])
        self.upper = np.concatenate([hi, s_hi])
        self.d = self.lower.size
        self.names = theta_names(self.terms)

    def __call__(self, theta) -> list:
        """[(N, T_k) deflection in mm for each curve k]."""
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        out = []
        for d in self.data:
            p_eff = effective_pressures(theta[:, 2:], d.time_s, d.pressure_mbar, d.breaks)
            out.append(self.elastic[d.probe_mm](theta[:, :2], p_eff))
        return out

    def parameters(self, theta) -> dict:
        theta = np.asarray(theta, dtype=float).reshape(-1)
        x1d = 10.0 ** theta[0]
        g, tau = prony_of(theta)
        factor = 1.0 + sum(g)
        return {"X1d": float(x1d), "X1h": float(x1d * 10.0 ** theta[1]), "g": g, "tau_s": tau,
                "X1d_instantaneous": float(x1d * factor),
                "X1h_instantaneous": float(x1d * 10.0 ** theta[1] * factor)}


class _Objective:
    """chi^2 / 2 (vectorised, for the window focusing) and whitened residuals."""

    error_unit = "1"

    def __init__(self, model: TimeCurveModel):
        self.model = model
        self.lower, self.upper = model.lower, model.upper
        self.n = sum(d.n for d in model.data)

    def whitened(self, theta) -> np.ndarray:
        """(N, n) residuals over sd of the used points; NaN where a candidate has no curve."""
        parts = [((d.deflection_mm - m) / d.sd_mm)[:, d.used]
                 for d, m in zip(self.model.data, self.model(theta))]
        return np.concatenate(parts, axis=1)

    def __call__(self, theta) -> np.ndarray:
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        chunk = max(8, 3_000_000 // max(self.n, 1))
        out = np.empty(theta.shape[0])
        for i in range(0, theta.shape[0], chunk):
            r = self.whitened(theta[i:i + chunk])
            out[i:i + chunk] = 0.5 * np.einsum("nt,nt->n", r, r)
        out[~np.isfinite(out)] = np.inf
        return out

    def error(self, cost) -> float:
        return math.sqrt(2.0 * cost / self.n)

    def residuals(self, theta) -> np.ndarray:
        r = self.whitened(np.asarray(theta, dtype=float)[None, :])[0]
        return np.where(np.isfinite(r), r, 1e6)

    def jacobian(self, theta, step: float = 1e-6) -> np.ndarray:
        """Forward differences in one vectorised call, stepping inward at a bound."""
        theta = np.asarray(theta, dtype=float)
        h = step * np.maximum(self.upper - self.lower, 1e-12)
        h = np.where(theta + h > self.upper, -h, h)
        pts = np.vstack([theta, theta + np.diag(h)])
        r = self.whitened(pts)
        r = np.where(np.isfinite(r), r, 1e6)
        return ((r[1:] - r[0]) / h[:, None]).T


@dataclass
class TimeFit:
    """A fitted model of time curves.

    ``phase_chi2``: per curve, phase -> (chi^2, points) over the used points;
    ``residual_um``: per curve, measured - fitted (every point, used or not).
    """

    terms: int
    theta: np.ndarray
    parameters: dict
    chi2: float
    n_points: int
    n_params: int
    fitted_mm: list
    residual_um: list
    phase_chi2: list
    wf: dict = field(default_factory=dict)

    @property
    def finite(self) -> bool:
        return math.isfinite(self.chi2)


def evaluate_time_fit(model: TimeCurveModel, theta, wf=None) -> TimeFit:
    """A :class:`TimeFit` at a given theta."""
    theta = sort_terms(theta)
    curves = [m[0] for m in model(theta[None, :])]
    chi2, fitted, res, per_phase = 0.0, [], [], []
    for d, m in zip(model.data, curves):
        z = (d.deflection_mm - m) / d.sd_mm
        chi2 += float(np.sum(z[d.used] ** 2))
        fitted.append(m)
        res.append(1e3 * (d.deflection_mm - m))
        per_phase.append({ph: (float(np.sum(z[(d.phase == ph) & d.used] ** 2)),
                               int(np.sum((d.phase == ph) & d.used)))
                          for ph in dict.fromkeys(d.phase)})
    if not math.isfinite(chi2):
        chi2 = math.inf
    n = sum(d.n for d in model.data)
    return TimeFit(model.terms, theta, model.parameters(theta), chi2, n, model.d, fitted, res,
                   per_phase, dict(wf or {}))


def fit_time_model(rays: dict, data: list, *, terms: int = 1, seed=0, repeats: int = 2,
                   window_focusing_options: dict | None = None, starts=(),
                   polish: bool = True) -> TimeFit:
    """Fit the model with ``terms`` Prony terms (0: elastic) to the curves ``data``.

    Parameters
    ----------
    rays : dict
        Probe (mm) -> neo-Hookean RaySpace.
    data : list of TimeFitData
    terms : {0, 1, 2}
    seed : int or SeedSequence
        ``repeats`` window focusing runs with seeds spawned from it.
    starts : sequence of theta
        Extra starting points for the polish (e.g. a nested model's fit).

    Returns
    -------
    TimeFit

    Raises
    ------
    IdentificationError
        When no candidate of the space reproduces the curves.
    """
    model = TimeCurveModel(rays, data, terms)
    obj = _Objective(model)
    wf = {**TIME_WF, **(window_focusing_options or {})}
    root = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence(seed)
    runs = []
    for s in root.spawn(int(repeats)):
        try:
            runs.append(window_focusing(obj, seed=s, **wf))
        except IdentificationError:
            continue
    cands = [r.estimate for r in runs]
    for s in starts:
        s = np.asarray(s, dtype=float)
        if s.size == model.d and np.isfinite(obj(s[None, :])[0]):
            cands.append(s)
    if not cands:
        raise IdentificationError("no parameters of the space reproduce the time curves "
                                  "(every candidate has no curve at the suction applied)")
    costs = [float(obj(np.asarray(c)[None, :])[0]) for c in cands]
    order = np.argsort(costs)
    best, best_cost = np.asarray(cands[order[0]], dtype=float), costs[order[0]]
    n_polished = 0
    if polish:
        lo, hi = obj.lower, obj.upper
        for i in order[:2]:
            x0 = np.clip(np.asarray(cands[i], dtype=float), lo, hi)
            try:
                sol = least_squares(obj.residuals, x0, jac=obj.jacobian, bounds=(lo, hi),
                                    method="trf", x_scale=np.maximum(hi - lo, 1e-12) * 0.05,
                                    xtol=1e-10, ftol=1e-10, gtol=1e-10, max_nfev=100)
            except ValueError:
                continue
            n_polished += 1
            c = float(obj(sol.x[None, :])[0])
            if c < best_cost:
                best, best_cost = sol.x, c
    info = {"runs": len(runs), "iterations": [int(r.iterations) for r in runs],
            "converged": [bool(r.converged) for r in runs],
            "chi2_runs": [2 * float(c) for c in costs[:len(runs)]],
            "polished": n_polished, "settings": wf, "repeats": int(repeats)}
    return evaluate_time_fit(model, best, info)


def _birge(chi2_min, dof, alpha=0.01) -> float:
    ratio = chi2_min / dof
    return float(ratio) if ratio > stats.chi2.ppf(1 - alpha, dof) / dof else 1.0


def laplace_intervals(rays: dict, data: list, fit: TimeFit, *, level: float = 0.95,
                      step: float = 1e-4, correlated: bool = True) -> dict:
    """Gauss-Newton (Laplace) intervals of every parameter of ``fit``.

    In theta (logs): ``theta_i +- sqrt(q s C_ii)``, C = (J^T J)^-1 from central
    differences (``step`` in log10 units), q the chi^2(1) quantile of ``level``, s
    the Birge ratio if the misfit is significant (else 1).  X1h and the
    instantaneous moduli are linear in theta's logs: their log-sd is g^T C g.
    An end beyond a bound of the space or of the spectrum is cut there and open.

    Returns
    -------
    dict
        JSON-able, the shape of :meth:`LikelihoodIntervals.to_dict`.
    """
    model = TimeCurveModel(rays, data, fit.terms)
    obj = _Objective(model)
    theta = np.asarray(fit.theta, dtype=float)
    d, n = theta.size, obj.n
    lo, hi = model.lower, model.upper
    pts = []
    for a in range(d):
        for s in (-1.0, 1.0):
            t = theta.copy()
            t[a] = np.clip(t[a] + s * step, lo[a], hi[a])
            pts.append(t)
    pts = np.array(pts)
    r = obj.whitened(pts)
    r = np.where(np.isfinite(r), r, np.nan)
    J = ((r[1::2] - r[0::2]) / (pts[1::2] - pts[0::2]).sum(axis=1)[:, None]).T  # (n, d)
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
    scale = _birge(fit.chi2, max(n - d, 1))
    q = interval_threshold(level) * scale
    # each reported quantity as a linear form of theta in log10 (exact in the logs)
    forms = {"X1d": np.eye(d)[0], "X1h": np.eye(d)[0] + np.eye(d)[1]}
    terms = fit.terms
    order = np.argsort(theta[3::2]) if terms else []
    for k, j in enumerate(order, start=1):
        forms[f"g_{k}"] = np.eye(d)[2 + 2 * j]
        forms[f"tau_{k}"] = np.eye(d)[3 + 2 * j]
    if terms:
        # log10(1 + sum g) by its derivative at the fit
        g = 10.0 ** theta[2::2]
        dlog = np.zeros(d)
        dlog[2::2] = g / (1.0 + g.sum())
        forms["X1d_instantaneous"] = forms["X1d"] + dlog
        forms["X1h_instantaneous"] = forms["X1h"] + dlog
    out = {}
    for name, a in forms.items():
        centre = float(a @ theta) if not name.endswith("instantaneous") else \
            float(a[:2] @ theta[:2] + math.log10(1.0 + (10.0 ** theta[2::2]).sum()))
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
        out[name] = {"estimate": 10.0 ** centre, "lower": 10.0 ** lower, "upper": 10.0 ** upper,
                     "lower_open": lo_open, "upper_open": up_open}
    sd = np.sqrt(np.maximum(np.diag(cov), 0.0))
    names = [k for k in forms if not k.endswith("instantaneous")]
    corr = {}
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            va, vb = forms[a], forms[b]
            den = math.sqrt(max(va @ cov @ va, 0) * max(vb @ cov @ vb, 0))
            corr[f"{a},{b}"] = float(va @ cov @ vb / den) if den > 0 else None
    method = ("Gauss-Newton (Laplace) approximation in log10 of each parameter, the "
              "covariance of the weighted least-squares estimate under a correlated model "
              "error (sandwich: Legendre terms per curve and phase, the space's accuracy "
              "along each curve), coverage measured by benchmarks/time_identify.py"
              if correlated else "Gauss-Newton (Laplace) approximation in log10 of each "
              "parameter, independent points, coverage measured by "
              "benchmarks/time_identify.py")
    return {"method": method,
            "level": float(level), **out, "correlation": corr, "chi2_min": float(fit.chi2),
            "delta_chi2_threshold": float(q), "misfit_scale": float(scale),
            "noise_dof": None, "n_points": int(n), "sd_log10": sd.tolist(),
            "correlated_model_error": bool(correlated), "chi2_correlated": chi2_corr,
            "systematic_terms": int(Bw.shape[1]),
            "notes": notes}


def time_bound_flags(rays: dict, data: list, fit: TimeFit, config_keys=None) -> dict:
    """``{parameter: flag}``: which fitted coordinates sit at an edge of the space (X1d,
    X1h/X1d: window or coverage) or of the spectrum's bounds (g_i, tau_i)."""
    model = TimeCurveModel(rays, data, fit.terms)
    obj = _Objective(model)
    theta = np.asarray(fit.theta, dtype=float)
    names = ["X1d", "X1h"] + [f"{k}_{i}" for i in range(1, fit.terms + 1) for k in ("g", "tau")]
    kinds = ["log", "log"] + ["axis"] * (2 * fit.terms)
    keys = config_keys or [(None, None)] * len(names)
    keys = list(keys) + [(f"the spectrum's bounds (g {_bounds_text('g')}, tau "
                          f"{_bounds_text('tau')} s)",) * 2] * (len(names) - len(keys))
    flags = bound_flags(obj, theta, names, kinds, keys)
    return {f["parameter"]: f for f in flags}


def _bounds_text(kind):
    from ._time_model import G_BOUNDS, TAU_BOUNDS_S

    lo, hi = G_BOUNDS if kind == "g" else TAU_BOUNDS_S
    return f"{lo:g}-{hi:g}"
