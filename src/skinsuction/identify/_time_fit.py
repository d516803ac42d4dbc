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
from ._window_focusing import IdentificationError
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

__all__ = ["MODEL_ERROR", "MODEL_ERROR_LAYERS", "STRAIN_SLOPE", "TIME_WF", "TIME_POLISH", "TimeFitData", "TimeFit", "TimeCurveModel",
           "TimeObjective", "evaluate_time_fit", "fit_data_of", "fit_time_model",
           "time_fit_data"]

#: The fast path's model error as an sd, fraction of the curve's largest deflection,
#: per phase: "on" (suction on), "release" (the first 0.1 s after a step's release),
#: "off" (the rest of its off time), "ramp" (every phase of a ramp cycle, mode 2),
#: "rest" (before the first suction: no load, no error).  Between the median draw's
#: RMS and the worst draw's largest error of the fast-path benchmark
#: (docs/viscoelasticity.md: on 0.02-0.03 % / 0.34 %; release 0.68 % / 2.27 %;
#: off 0.22 % / 1.34 %; mode 2 0.03 % / 0.16 %).
MODEL_ERROR = {"on": 0.001, "release": 0.01, "off": 0.004, "ramp": 0.001, "rest": 0.0}

#: Growth of the fast path's model error with the strain of the curve, ``s = U / (a/2)``
#: (the largest deflection over the aperture's radius): its error is the departure from
#: linear theory, so it grows with the strain (docs/effects.md: release errors of
#: 0.2-0.5 % of Uf at s < 0.1, 1-4 % at s = 0.15-0.35, on 2-8 mm probes).  The sd of a
#: phase is ``max(MODEL_ERROR[phase], STRAIN_SLOPE[phase] * s)``: about 0.45 times the
#: worst error measured at that strain.
STRAIN_SLOPE = {"on": 0.01, "release": 0.054, "off": 0.03, "ramp": 0.005, "rest": 0.0}

#: The model error of the per-layer fast path (:class:`TimeCurveModel` with
#: ``layers=True``), fraction of the curve's largest deflection in every loaded phase:
#: its measured error against FE time solves with a spectrum per layer is 0.4-2.8 %
#: of Uf (docs/effects.md, "Which layer creeps").
MODEL_ERROR_LAYERS = {"on": 0.02, "release": 0.02, "off": 0.02, "ramp": 0.02, "rest": 0.0}

#: Seconds after a step's release counted as "release" (where Ur is read).
RELEASE_S = 0.1

#: Window focusing of the time fits: the paper's N and Nb, a looser stop (in units
#: of sqrt(chi^2 / n)) and fewer iterations: the polish finishes the job.
TIME_WF = {"n_samples": 1000, "n_best": 20, "tolerance": 1e-4, "max_iter": 60}

#: The window focusing of the time fits reads every ``stride``-th sample, and every
#: sample a geometric ladder of offsets after each change of the suction's slope (the
#: creep transients, 1 ms to 10 s, alike in log time): a fifth of a mode-1 curve's
#: samples. The polish then runs on them all (:func:`search_samples`).
TIME_SEARCH_STRIDE = 8

#: The polish of the time fits: the objective's own Jacobian (forward differences in
#: one vectorised call), a looser tolerance and fewer evaluations than the engine's
#: :data:`skinsuction.identify.POLISH`; a residual without a curve counts as 1e6 sd.
TIME_POLISH = {"max_nfev": 100, "tol": 1e-10, "diff_step": None, "jacobian": True,
               "nonfinite": 1e6}


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
        Fractions per phase; default :data:`MODEL_ERROR`, raised with the curve's strain
        (:data:`STRAIN_SLOPE`).
    phases : {"all", "on"}
        ``"on"``: only the points while the suction is on (and before it) are fitted.

    Returns
    -------
    TimeFitData
    """
    if phases not in ("all", "on"):
        raise ValueError(f"phases must be 'all' or 'on', not {phases!r}")
    p, note = clean_pressure(curve)
    d = np.asarray(curve.deflection_mm, dtype=float)
    phase = _phases(curve)
    sigma = float(curve.noise_sd_mm if noise_sd_mm is None else noise_sd_mm)
    if not sigma > 0:
        raise ValueError(f"{curve.label}: the noise sd must be positive (the curve shows "
                         "none: give it, --noise-um)")
    used = None if phases == "all" else np.isin(phase, ["rest", "on", "ramp"])
    return time_fit_data(curve.label, curve.probe_mm, curve.time_s, p, d, phase, sigma,
                         model_error=model_error, used=used, notes=(note,),
                         resolution_mm=float(getattr(curve, "resolution_mm", None)
                                             or _grid_step(d)))


def time_fit_data(label, probe_mm, time_s, pressure_mbar, deflection_mm, phase, noise_sd_mm,
                  *, model_error=None, used=None, notes=(), resolution_mm=0.0) -> TimeFitData:
    """A :class:`TimeFitData` from its arrays: each point's sd is the noise, the fast
    path's error in its phase and the space's accuracy (what :func:`fit_data_of` does
    for a loaded curve; a design's noise-free curves use it too).

    Parameters
    ----------
    phase : array of str
        ``rest``, ``on``, ``release``, ``off`` or ``ramp`` per point.
    noise_sd_mm : float
        The noise sd of one deflection (mm), > 0.
    model_error : dict, optional
        Fractions per phase; default :data:`MODEL_ERROR`, raised with the curve's strain
        (:data:`STRAIN_SLOPE`).
    used : array of bool, optional
        The points in the likelihood (default all).
    """
    d = np.asarray(deflection_mm, dtype=float)
    phase = np.asarray(phase, dtype=object)
    sigma = float(noise_sd_mm)
    scale = float(np.percentile(np.abs(d), 99.5))
    if model_error is None:
        # the fast path's error grows with the strain (STRAIN_SLOPE)
        strain = scale / (0.5 * float(probe_mm))
        fractions = {k: max(v, STRAIN_SLOPE.get(k, 0.0) * strain)
                     for k, v in MODEL_ERROR.items()}
    else:
        fractions = {**MODEL_ERROR, **model_error}
    f = np.array([fractions[k] for k in phase], dtype=float)
    # the space's own accuracy target (0.2 % of M and 0.3 µm), as for pressure ramps
    from .measured_fit import MODEL_ERROR_MM, MODEL_ERROR_RELATIVE

    sd = np.sqrt(sigma ** 2 + (f * scale) ** 2 + (MODEL_ERROR_RELATIVE * d) ** 2
                 + MODEL_ERROR_MM ** 2 * (phase != "rest"))
    used = np.ones(d.size, bool) if used is None else np.asarray(used, bool)
    t = np.asarray(time_s, dtype=float)
    p = np.asarray(pressure_mbar, dtype=float)
    return TimeFitData(label, float(probe_mm), t, p, d, sd, phase, sigma, scale, used,
                       pressure_breaks(t, p), tuple(notes), fractions, float(resolution_mm))


def search_samples(d: TimeFitData, stride: int = TIME_SEARCH_STRIDE) -> TimeFitData:
    """The curve ``d`` at the samples the window focusing reads.

    Every ``stride``-th sample, every break of the suction's slope, and after each
    break the samples at offsets 1, 2, 3, 4, 5, 8, 11, 15, ... (each about 1.4 times
    the last): the fast transients stay dense, the slow ones and the elastic curve are
    read every ``stride`` samples. The suction is linear between its breaks, so the
    model at the kept samples is exactly the model of the whole curve there
    (:func:`effective_pressures`); only the sum of squares has fewer terms.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(101) * 0.01
    >>> p = np.where(t >= 0.2, 100.0, 0.0); p[20] = 50.0     # a step at 0.2 s
    >>> d = time_fit_data("x", 2.0, t, p, 0.1 * p / 100, np.full(101, "on"), 0.003)
    >>> s = search_samples(d, stride=10)
    >>> s.time_s.size, [round(float(v), 2) for v in s.time_s[:12]]
    (32, [0.0, 0.01, 0.02, 0.03, 0.04, 0.05, 0.08, 0.1, 0.11, 0.15, 0.19, 0.2])
    >>> bool(np.all(np.isin(d.time_s[d.breaks], s.time_s)))
    True
    """
    size = d.time_s.size
    if stride <= 1 or size <= 2 * stride:
        return d
    breaks = d.breaks if d.breaks is not None else pressure_breaks(d.time_s, d.pressure_mbar)
    ladder = np.unique(np.round(1.4 ** np.arange(int(np.log(size) / np.log(1.4)) + 2)))
    keep = np.zeros(size, bool)
    keep[::stride] = True
    keep[[0, size - 1]] = True
    ends = np.append(breaks[1:], size - 1)
    for a, b in zip(breaks, ends):
        offsets = ladder[ladder < min(b - a, 8 * stride)].astype(int)
        keep[a] = True
        keep[a + offsets] = True
    idx = np.flatnonzero(keep)
    return replace(d, time_s=d.time_s[idx], pressure_mbar=d.pressure_mbar[idx],
                   deflection_mm=d.deflection_mm[idx], sd_mm=d.sd_mm[idx],
                   phase=d.phase[idx], used=d.used[idx],
                   breaks=np.searchsorted(idx, breaks).astype(int))


def _grid_step(d) -> float:
    """The grid the deflections lie on, 0 if none: the loader's rule without its
    20-step range (that misses a small curve, 0.08 mm at 0.01 mm under a 2 mm probe)."""
    from skinsuction.measured import grid_step

    return grid_step(d, min_steps=2) or 0.0


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
