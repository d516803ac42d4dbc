"""Fit the elastic (g = 0) or viscoelastic model to time curves: the core.

:func:`fit_time_model` fits ``theta = (log10 X1d, log10 X1h/X1d[, u][, log10 g_i,
log10 tau_i ...])`` (``u`` the axis coordinate of an elastic cause, such as the
dermis's strain stiffening X2d/X1d, when the rays are that cause's; 0, 1 or 2
Prony terms, one spectrum for both layers) to one
or more time curves (:class:`TimeFitData`, e.g. two probes of one skin) with the
fast path on the scale-free space (:mod:`._time_model`), by the fitting engine
(:func:`skinsuction.identify.repeated_fit`): window focusing in the box of the
space and the spectrum's bounds (paper section 2.4, a looser stop,
:data:`TIME_WF`), the best runs polished by bounded least squares
(:data:`TIME_POLISH`, with the objective's own Jacobian).  It returns
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
:func:`skinsuction.identify.laplace_intervals` (:mod:`._time_intervals`), with the
model error as a correlated (systematic) term along each curve.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ._engine import Chi2Objective, repeated_fit
from ._time_data import (  # noqa: F401  (the data side, re-exported here)
    MODEL_ERROR,
    MODEL_ERROR_LAYERS,
    RELEASE_S,
    STRAIN_SLOPE,
    TIME_SEARCH_STRIDE,
    TimeFitData,
    _grid_step,
    fit_data_of,
    search_samples,
    time_fit_data,
)
from ._window_focusing import IdentificationError
from ._time_model import (
    ElasticRays,
    effective_pressures,
    prony_of,
    sort_terms,
    spectrum_bounds,
    theta_names,
)

__all__ = ["MODEL_ERROR", "MODEL_ERROR_LAYERS", "STRAIN_SLOPE", "TIME_WF", "TIME_POLISH", "TimeFitData", "TimeFit", "TimeCurveModel",
           "TimeObjective", "evaluate_time_fit", "fit_data_of", "fit_time_model",
           "time_fit_data"]

#: Window focusing of the time fits: the paper's N and Nb, a looser stop (in units
#: of sqrt(chi^2 / n)) and fewer iterations: the polish finishes the job.
TIME_WF = {"n_samples": 1000, "n_best": 20, "tolerance": 1e-4, "max_iter": 60}

#: The polish of the time fits: the objective's own Jacobian (forward differences in
#: one vectorised call), a looser tolerance and fewer evaluations than the engine's
#: :data:`skinsuction.identify.POLISH`; a residual without a curve counts as 1e6 sd.
TIME_POLISH = {"max_nfev": 100, "tol": 1e-10, "diff_step": None, "jacobian": True,
               "nonfinite": 1e6}


class TimeCurveModel:
    """Deflections of candidates theta on every fitted curve (the fast path).

    ``rays`` maps probe (mm) to its :class:`~skinsuction.space.RaySpace`
    (``LoadedSpace.probe(p).space``): the neo-Hookean one, or one cause's
    (:meth:`skinsuction.space.LoadedSpace.cause_rays`, e.g. strain stiffening:
    the fast path then drives the nonlinear elastic curve of that skin, and theta
    holds the cause's axis coordinate after X1h/X1d); ``terms`` Prony terms (0:
    elastic).  :attr:`k0` is where the spectrum starts in theta (2, or 3 with a
    cause).
    """

    def __init__(self, rays: dict, data: list, terms: int, layers: bool = False):
        if terms not in (0, 1, 2):
            raise ValueError(f"0, 1 or 2 Prony terms, not {terms}")
        if layers and terms != 1:
            raise ValueError("a spectrum per layer has one term each (terms=1)")
        self.data, self.terms, self.layers = list(data), int(terms), bool(layers)
        self.elastic = {}
        for p in sorted({d.probe_mm for d in self.data}):
            p_max = max(float(d.pressure_mbar.max()) for d in self.data if d.probe_mm == p)
            self.elastic[p] = ElasticRays(rays[p], p, p_max)
        causes = {None if e.cause is None else e.cause.name for e in self.elastic.values()}
        if len(causes) != 1:
            raise ValueError(f"the probes' spaces hold different causes: {sorted(map(str, causes))}")
        #: the elastic cause of the spaces (None: neo-Hookean)
        self.cause = next(iter(self.elastic.values())).cause
        lo = np.max([e.lower for e in self.elastic.values()], axis=0)
        hi = np.min([e.upper for e in self.elastic.values()], axis=0)
        self.k0 = lo.size
        s_lo, s_hi = spectrum_bounds(2 if self.layers else self.terms)
        self.lower = np.concatenate([lo, s_lo])
        self.upper = np.concatenate([hi, s_hi])
        self.d = self.lower.size
        self.names = theta_names(self.terms, self.cause)
        if self.layers:
            self.names = self.names[:self.k0] + ["log10 g_dermis", "log10 tau_dermis",
                                                 "log10 g_hypodermis", "log10 tau_hypodermis"]

    def __call__(self, theta) -> list:
        """[(N, T_k) deflection in mm for each curve k]."""
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        k0, out = self.k0, []
        for d in self.data:
            if self.layers:
                p_eff = self._layer_pressures(theta, d)
            else:
                p_eff = effective_pressures(theta[:, k0:], d.time_s, d.pressure_mbar, d.breaks)
            out.append(self.elastic[d.probe_mm](theta[:, :k0], p_eff))
        return out

    def hypodermis_share(self, theta, probe_mm: float, p_mbar: float) -> np.ndarray:
        """beta (N,): the hypodermis's share of the compliance of the elastic curve at
        ``p_mbar``: -d log M / d log X1h over d log M / d log p (the two sum to it by
        the scaling law), clipped to [0, 1]."""
        el, th = self.elastic[probe_mm], np.asarray(theta, dtype=float)[:, :self.k0]
        h = 0.005  # in log10 units (1.2 %)
        p0 = np.full((th.shape[0], 1), float(p_mbar))
        with np.errstate(all="ignore"):
            m0 = el(th, p0)[:, 0]
            tr = th.copy()
            step = np.where(tr[:, 1] + h <= self.upper[1], h, -h)
            tr[:, 1] += step
            w_h = -(np.log(el(tr, p0)[:, 0]) - np.log(m0)) / (step * math.log(10.0))
            pp = p0 * 10.0 ** h
            n = (np.log(el(th, pp)[:, 0]) - np.log(m0)) / (h * math.log(10.0))
            beta = np.clip(w_h / n, 0.0, 1.0)
        return np.where(np.isfinite(beta), beta, 0.5)

    def _layer_pressures(self, theta, d) -> np.ndarray:
        """The per-layer fast path's drive: ``(1 - beta) p_eff,dermis + beta p_eff,hypodermis``,
        each layer's spectrum through its own creep function, weighed by the
        hypodermis's share of the compliance at the curve's largest suction (exact for
        one spectrum, and in the linear limit where one layer carries the compliance)."""
        k0 = self.k0
        pd_ = effective_pressures(theta[:, k0:k0 + 2], d.time_s, d.pressure_mbar, d.breaks)
        ph = effective_pressures(theta[:, k0 + 2:k0 + 4], d.time_s, d.pressure_mbar, d.breaks)
        beta = self.hypodermis_share(theta, d.probe_mm, float(d.pressure_mbar.max()))
        return (1.0 - beta)[:, None] * pd_ + beta[:, None] * ph

    def cause_value(self, theta) -> float | None:
        """The cause's parameter at theta (e.g. X2d in MPa), None without a cause."""
        if self.cause is None:
            return None
        theta = np.asarray(theta, dtype=float).reshape(-1)
        c = float(self.cause.from_axis(theta[2]))
        return float(self.cause.value(coordinate=c, dermis_X1=10.0 ** theta[0]))

    def parameters(self, theta) -> dict:
        theta = np.asarray(theta, dtype=float).reshape(-1)
        x1d = 10.0 ** theta[0]
        if self.layers:
            k0 = self.k0
            out = {"X1d": float(x1d), "X1h": float(x1d * 10.0 ** theta[1]), "g": [], "tau_s": [],
                   "g_dermis": [float(10.0 ** theta[k0])],
                   "tau_s_dermis": [float(10.0 ** theta[k0 + 1])],
                   "g_hypodermis": [float(10.0 ** theta[k0 + 2])],
                   "tau_s_hypodermis": [float(10.0 ** theta[k0 + 3])]}
            if self.cause is not None:
                out[self.cause.symbol] = self.cause_value(theta)
            return out
        g, tau = prony_of(theta, self.k0)
        factor = 1.0 + sum(g)
        out = {"X1d": float(x1d), "X1h": float(x1d * 10.0 ** theta[1]), "g": g, "tau_s": tau,
               "X1d_instantaneous": float(x1d * factor),
               "X1h_instantaneous": float(x1d * 10.0 ** theta[1] * factor)}
        if self.cause is not None:
            out[self.cause.symbol] = self.cause_value(theta)
        return out


class TimeObjective(Chi2Objective):
    """chi^2 / 2 of the whitened residuals of every fitted curve (one block), for the
    engine; the cost is evaluated a few candidates at a time (long curves)."""

    def __init__(self, model: TimeCurveModel):
        super().__init__(model.lower, model.upper, sum(d.n for d in model.data),
                         chunk_values=3_000_000)
        self.model = model

    def whitened(self, theta) -> np.ndarray:
        """(N, n) residuals over sd of the used points; NaN where a candidate has no curve."""
        parts = [((d.deflection_mm - m) / d.sd_mm)[:, d.used]
                 for d, m in zip(self.model.data, self.model(theta))]
        return np.concatenate(parts, axis=1)

    def blocks(self, theta) -> list:
        """One block: :meth:`whitened`."""
        return [self.whitened(theta)]

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
    cause: str | None = None  # the elastic cause of the space fitted (None: neo-Hookean)
    layers: bool = False  # a spectrum per layer (one term each)

    @property
    def finite(self) -> bool:
        return math.isfinite(self.chi2)


def evaluate_time_fit(model: TimeCurveModel, theta, wf=None) -> TimeFit:
    """A :class:`TimeFit` at a given theta.

    Parameters
    ----------
    model : TimeCurveModel
    theta : array_like (d,)
        Its Prony terms are sorted by tau.
    wf : dict, optional
        What the search did (:meth:`skinsuction.identify.FitResult.summary`).

    Returns
    -------
    TimeFit
    """
    theta = (np.asarray(theta, dtype=float).reshape(-1) if model.layers
             else sort_terms(theta, model.k0))
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
                   per_phase, dict(wf or {}),
                   None if model.cause is None else model.cause.name, model.layers)


def fit_time_model(rays: dict, data: list, *, terms: int = 1, seed=0, repeats: int = 2,
                   window_focusing_options: dict | None = None, starts=(),
                   polish: bool = True, layers: bool = False,
                   search_stride: int = TIME_SEARCH_STRIDE) -> TimeFit:
    """Fit the model with ``terms`` Prony terms (0: elastic) to the curves ``data``.

    Parameters
    ----------
    rays : dict
        Probe (mm) -> RaySpace: the neo-Hookean one, or an elastic cause's (its
        axis coordinate is then fitted too, :class:`TimeCurveModel`).
    data : list of TimeFitData
    terms : {0, 1, 2}
    seed : int or SeedSequence
        ``repeats`` window focusing runs with seeds spawned from it.
    repeats : int
        Window focusing runs (the engine's :func:`~skinsuction.identify.repeated_fit`).
    window_focusing_options : dict, optional
        Overrides :data:`TIME_WF`.
    starts : sequence of theta
        Extra starting points for the polish (e.g. a nested model's fit).
    polish : bool
        Polish the two best candidates (:data:`TIME_POLISH`).
    layers : bool
        A spectrum per layer, one term each (``terms=1``): the per-layer fast path of
        :class:`TimeCurveModel`, an approximation whose error
        (:data:`MODEL_ERROR_LAYERS`) the data's sd must carry.
    search_stride : int
        The window focusing reads the samples of :func:`search_samples` with this
        stride (1: every sample); the polish reads every sample.

    Returns
    -------
    TimeFit

    Raises
    ------
    IdentificationError
        When no candidate of the space reproduces the curves.
    """
    model = TimeCurveModel(rays, data, terms, layers)
    wf = {**TIME_WF, **(window_focusing_options or {})}
    error = ("no parameters of the space reproduce the time curves "
             "(every candidate has no curve at the suction applied)")
    search = model
    if repeats > 0 and search_stride > 1:
        search = TimeCurveModel(rays, [search_samples(d, search_stride) for d in data],
                                terms, layers)
    fit = repeated_fit(TimeObjective(search), repeats=repeats, seed=seed, starts=starts,
                       focus_options=wf, polish_best=2 if polish else 0,
                       polish_options=TIME_POLISH, error_message=error)
    if search is not model:
        # the estimate is the polish on every sample, from the search's best and the
        # given starts (a nested model's fit stays within reach)
        try:
            final = repeated_fit(TimeObjective(model), repeats=0, starts=[fit.x, *starts],
                                 polish_best=2 if polish else 0, polish_options=TIME_POLISH,
                                 error_message=error)
        except IdentificationError:  # no curve at a sample the search skipped: search all
            return fit_time_model(rays, data, terms=terms, seed=seed, repeats=repeats,
                                  window_focusing_options=window_focusing_options,
                                  starts=starts, polish=polish, layers=layers, search_stride=1)
        fit = replace(fit, x=final.x, cost=final.cost, polished=fit.polished + final.polished,
                      settings={**fit.settings, "search_stride": int(search_stride),
                                "search_points": sum(d.n for d in search.data)})
    return evaluate_time_fit(model, fit.x, fit.summary())
