"""Fit a model (neo-Hookean or one cause) on its ray space with the fitting engine.

The parameters searched are ``theta = (log10 X1d, log10 r[, c])`` with
``r = X1h / X1d`` and ``u`` the axis coordinate of the cause (its ray
coordinate on the cause's scale, :meth:`Cause.to_axis`; see :mod:`._rays`): the window focusing of the paper (section 2.4, N = 1000,
Nb = 20) samples uniformly in the box of the space, which in logarithms covers
decades of moduli evenly.  The cost is ``chi^2 / 2`` with the noise level of
each point, so both probes weigh by their noise (a
:class:`skinsuction.identify.Chi2Objective`, one block per probe).  The fit is the
engine's :func:`skinsuction.identify.repeated_fit`: the best of ``repeats``
window focusing runs (independent seeds) and of the given starts is polished by a
bounded least-squares (trust region), so that the chi^2 that the BIC compares is
the minimum and not the stochastic stop of the window focusing; its intervals are
the engine's profile likelihood (:func:`skinsuction.identify.profile_intervals`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
from skinsuction.identify import Chi2Objective, bound_flags, profile_intervals, repeated_fit
from skinsuction.identify.measured_fit import (decorrelate, discretisation_error_rms,
                                               space_error_direction)

from skinsuction.space import RayInterpolant, RaySpace, interpolant, read_at_once, space_causes

__all__ = ["FitData", "Fit", "ModelCurves", "fit_model", "fit_bounds", "fit_intervals",
           "with_space_error", "PAPER_WF", "DIAGNOSIS_POLISH"]

#: Window focusing settings of the paper (section 2.4); C in units of sqrt(chi^2/n).
PAPER_WF = {"n_samples": 1000, "n_best": 20, "tolerance": 1e-6, "max_iter": 200}

#: The polish of the engine (:data:`skinsuction.identify.POLISH`), a residual without a
#: curve counted as 1e6 noise sd.
DIAGNOSIS_POLISH = {"nonfinite": 1e6}


@dataclass(frozen=True)
class FitData:
    """The points fitted for one probe: pressures (mbar), deflections (mm), noise sd (µm)."""

    probe_mm: float
    pressure_mbar: np.ndarray
    deflection_mm: np.ndarray
    sigma_um: float
    curve_ids: tuple = ()
    #: (unit direction, gamma, scale) of the space's correlated error along the curve
    #: and of each point's own (:func:`with_space_error`), or None: the noise alone
    space_error: tuple | None = None

    @property
    def n(self) -> int:
        return int(self.pressure_mbar.size)

    def whiten(self, z: np.ndarray) -> np.ndarray:
        """Residuals in units of sigma (N, n) -> independent unit-variance ones."""
        if self.space_error is None:
            return z
        a, gamma, scale = self.space_error
        return decorrelate(z * scale, a, gamma)


def with_space_error(data: dict, x1d_mpa: float, *, point_scale: float = 1.0) -> dict:
    """``data`` ({probe: FitData}) with the space's correlated error of each probe.

    The error of the scale-free space against direct FE runs is smooth along a
    curve and grows with the load p / X1d (soft skin under the 6 mm probe); it
    enters each probe's likelihood as one rank-one covariance term, as in the
    identification's intervals (:func:`skinsuction.identify.measured_fit.space_error_direction`,
    measured by ``benchmarks/space_error_profile.py``).  The load of a point is taken
    at ``x1d_mpa`` (the baseline's X1d): every model of the diagnosis then weighs
    the points alike.

    Parameters
    ----------
    data : dict
        ``{probe_mm: FitData}``.
    x1d_mpa : float
        The X1d at which the load of each point is read.
    point_scale : float
        Scales the discretisation's own share of each point's sd, as the noise's
        was: a design's prediction fits every k-th point of a curve at sd
        ``sigma * sqrt(k / n)`` (the same information), and its points stand for
        ``n / k`` points each, of the discretisation's wiggles too.

    Returns
    -------
    dict
        ``{probe_mm: FitData}`` with ``space_error`` set (None where there is none).
    """
    out = {}
    for p, d in data.items():
        # each point's sd: the noise and the discretisation's error (its wiggles along
        # the curve); the correlated term is then read in those units
        sd0 = 1e-3 * d.sigma_um
        sd = np.hypot(sd0, point_scale * discretisation_error_rms(p, d.deflection_mm)
                      * np.abs(d.deflection_mm))
        a, gamma = space_error_direction(p, d.pressure_mbar, d.deflection_mm, x1d_mpa, sd)
        out[p] = replace(d, space_error=(a, gamma, sd0 / sd))
    return out


class ModelCurves:
    """Curves of one model at the measured pressures of several probes.

    A given layer thickness with an sd (``space.nuisance``, see
    :class:`skinsuction.space.ThicknessNuisance`) adds one coordinate per
    thickness to theta: its offset ``delta`` in sd units, searched in
    ``[-NUISANCE_RANGE, NUISANCE_RANGE]`` with a standard normal prior (the
    objective adds ``delta**2`` to chi^2).  The model's curve moves with it by the
    quadratic through its brackets' curves at -1, 0 and +1 sd: the model's own
    (a cause solved at the given layers) or, else, the neo-Hookean ones at the same
    (X1d, X1h).
    """

    def __init__(self, space: RaySpace, data: dict):
        self.space = space
        self.data = data
        self.interp = {p: interpolant(space, p, d.pressure_mbar) for p, d in data.items()}
        self.causes = space_causes(space)
        first = next(iter(self.interp.values()))
        self.nuisance = tuple(getattr(space, "nuisance", ()) or ())
        self.n_model = first.d
        self._brackets = [
            {p: tuple(RayInterpolant(s, p, d.pressure_mbar) for s in (n.center, n.minus, n.plus))
             for p, d in data.items()} for n in self.nuisance]
        k = len(self.nuisance)
        self.lower = np.concatenate([first.lower, np.full(k, -NUISANCE_RANGE)])
        self.upper = np.concatenate([first.upper, np.full(k, NUISANCE_RANGE)])
        self.d = self.n_model + k

    def __call__(self, theta) -> dict:
        theta = np.asarray(theta, dtype=float)
        own = theta[:, :self.n_model]
        out = {}
        for p, f in self.interp.items():
            # the model and every bracket are read at the same X1d: at once
            calls = [(f, own)]
            for n, brackets in zip(self.nuisance, self._brackets):
                # a cause's own brackets are read at its coordinate too; brackets
                # centred on this model's own space have its curve as their centre
                at = own if n.center.cause is not None else own[:, :2]
                center, minus, plus = brackets[p]
                calls += [(minus, at), (plus, at)] + (
                    [] if n.center is self.space else [(center, at)])
            curves = iter(read_at_once(calls))
            model = next(curves)
            out[p] = model
            for j, n in enumerate(self.nuisance):
                delta = theta[:, self.n_model + j][:, None]
                lo, hi = next(curves), next(curves)
                m0 = model if n.center is self.space else next(curves)
                out[p] = out[p] + delta * (hi - lo) / 2 + delta ** 2 * (hi + lo - 2 * m0) / 2
        return out

    def prior(self, theta) -> np.ndarray:
        """``delta**2`` summed over the nuisance coordinates, (N,)."""
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        return np.sum(theta[:, self.n_model:] ** 2, axis=1)

    def parameters(self, theta) -> dict:
        """Physical parameters (MPa, mm, 1) of one theta."""
        x1d = 10.0 ** theta[0]
        out = {"X1d": float(x1d), "X1h": float(x1d * 10.0 ** theta[1])}
        for k, cause in enumerate(self.causes):
            out[cause.symbol] = float(cause.value(cause.from_axis(theta[2 + k]), x1d))
        for j, n in enumerate(self.nuisance):
            out[n.symbol] = float(n.thickness(theta[self.n_model + j]))
        return out


def nested_start(base_theta, cause, at: int = 2) -> np.ndarray:
    """A cause's theta at its neutral value from the theta of the model it extends.

    The cause's coordinate goes at ``at``: after (X1d, X1h/X1d) and before any
    thickness nuisance, as :class:`ModelCurves` orders them, for a cause added to
    the neo-Hookean model; after the first cause's (``at=3``) for the second of a
    pair added to the first, or before it (``at=2``) for the first added to the
    second.  The extended model then fits at least as well as the one it extends.

    Parameters
    ----------
    base_theta : array_like
        The extended model's theta (log10 X1d, log10 X1h/X1d[, cause axis],
        thickness offsets).
    cause : Cause
    at : int
        Where the cause's coordinate goes.

    Returns
    -------
    ndarray

    Examples
    --------
    >>> from skinsuction.space import default_registry
    >>> nested_start([-1.4, -2.0, 0.3], default_registry()["pre_tension"])
    array([-1.4, -2. ,  1. ,  0.3])
    """
    t = np.asarray(base_theta, dtype=float)
    return np.concatenate([t[:at], [cause.to_axis(cause.neutral)], t[at:]])


#: Search range of a thickness nuisance, in sd units either side of the given value.
NUISANCE_RANGE = 3.0


class _Objective(Chi2Objective):
    """chi^2 / 2 of the probes' whitened residuals (one block per probe) and the
    thickness prior's terms: the engine's objective of a diagnosis fit."""

    def __init__(self, model: ModelCurves):
        super().__init__(model.lower, model.upper, sum(d.n for d in model.data.values()))
        self.model = model

    def blocks(self, theta) -> list:
        """Each probe's residuals in units of its noise, decorrelated, ``[(N, n_p)]``."""
        out = []
        for p, m in self.model(theta).items():
            d = self.model.data[p]
            out.append(d.whiten((d.deflection_mm[None, :] - m) * (1e3 / d.sigma_um)))
        return out

    def prior_residuals(self, theta) -> np.ndarray:
        """The thickness offsets in sd units, ``(N, nuisances)``: their prior."""
        return theta[:, self.model.n_model:]


@dataclass
class Fit:
    """A fitted model."""

    model: str
    theta: np.ndarray
    parameters: dict
    chi2: float
    n_points: int
    n_params: int
    E_um: float  # eq. 7 on the concatenated residuals of the fitted probes
    rms_um: float
    fitted_mm: dict  # probe -> (u,)
    residual_um: dict  # probe -> (u,)
    wf: dict = field(default_factory=dict)
    #: probe -> residuals (µm) with the space's correlated error taken out (independent
    #: points of sd sigma, what the misfit test judges); the residuals if it is not used
    independent_um: dict = field(default_factory=dict)

    @property
    def finite(self) -> bool:
        return math.isfinite(self.chi2)


def _curves_at(model: ModelCurves, theta):
    return {p: c[0] for p, c in model(np.asarray(theta)[None, :]).items()}


def evaluate_fit(model: ModelCurves, theta, name: str, wf=None) -> Fit:
    """A :class:`Fit` at a given theta (chi^2, E, residuals).

    Parameters
    ----------
    model : ModelCurves
    theta : array_like
    name : str
        The model's name (the space's).
    wf : dict, optional
        What the search did (:meth:`skinsuction.identify.FitResult.summary`).

    Returns
    -------
    Fit
    """
    curves = _curves_at(model, theta)
    chi2, sq, n = 0.0, 0.0, 0
    res, independent = {}, {}
    for p, c in curves.items():
        d = model.data[p]
        e = 1e3 * (d.deflection_mm - c)
        res[p] = e
        z = d.whiten((e / d.sigma_um)[None, :])[0]
        independent[p] = z * d.sigma_um
        chi2 += float((z ** 2).sum())
        sq += float((e ** 2).sum())
        n += d.n
    chi2 += float(model.prior(theta)[0])  # a given thickness's prior term
    if not math.isfinite(chi2):
        chi2 = sq = math.inf
    return Fit(name, np.asarray(theta, dtype=float), model.parameters(theta), chi2, n,
               model.d, math.sqrt(sq) / n, math.sqrt(sq / n), curves, res, dict(wf or {}),
               independent)


def fit_model(space: RaySpace, data: dict, *, seed=0, repeats: int = 2,
              window_focusing_options: dict | None = None, polish: bool = True,
              starts=()) -> Fit:
    """Fit the model of ``space`` to ``data`` by the engine's :func:`repeated_fit`.

    Parameters
    ----------
    space : RaySpace
        The model's ray space (neo-Hookean or one cause).
    data : dict
        ``{probe_mm: FitData}``.
    seed : int or numpy.random.SeedSequence
        ``repeats`` window focusing runs with seeds spawned from it.
    repeats : int
        Window focusing runs (0: only the ``starts``).
    window_focusing_options : dict, optional
        Overrides :data:`PAPER_WF`.
    polish : bool
        Polish the two best candidates by bounded least squares
        (:data:`DIAGNOSIS_POLISH`).
    starts : sequence of theta
        More candidates, e.g. a nested model's fit (:func:`nested_start`).

    Returns
    -------
    Fit
        ``wf``: the runs, their chi^2, the polishes and the settings.

    Raises
    ------
    IdentificationError
        No candidate of the space gives a finite cost.
    """
    model = ModelCurves(space, data)
    wf = {**PAPER_WF, **(window_focusing_options or {})}
    fit = repeated_fit(_Objective(model), repeats=repeats, seed=seed, starts=starts,
                       focus_options=wf, polish_best=2 if polish else 0,
                       polish_options=DIAGNOSIS_POLISH,
                       error_message=f"{space.name}: no parameters of the space reproduce the "
                                     "measured pressures (all candidates non-converged)")
    return evaluate_fit(model, fit.x, space.name, fit.summary())


def fit_bounds(space: RaySpace, data: dict, theta) -> dict:
    """``{parameter: flag}``: which fitted parameters sit at an edge of the space.

    See :func:`skinsuction.identify.bound_flags`; each flag names the
    configuration key that widens the space there.  A cause's parameter at its
    neutral end (e.g. X2d = 0) is the baseline model, not an edge: its flag has
    ``neutral: True``.

    Parameters
    ----------
    space : RaySpace
        The fitted model's ray space.
    data : dict
        ``{probe_mm: FitData}``, as fitted.
    theta : array_like
        The fit.

    Returns
    -------
    dict
        ``{parameter: flag}`` (the flags of :func:`skinsuction.identify.bound_flags`
        with ``value`` and ``neutral``).
    """
    model = ModelCurves(space, data)
    obj = _Objective(model)
    spec, causes = space.spec, space_causes(space)
    raised = model.lower[0] > math.log10(spec.x1d_range[0]) + 1e-12
    x1d_lo = ("scale_free_space.load.max (the largest measured pressure over load.max sets "
              "the lowest X1d)" if raised else "scale_free_space.x1d_mpa.min")
    names, kinds = ["X1d", "X1h"], ["log", "log"]
    keys = [(x1d_lo, "scale_free_space.x1d_mpa.max"),
            ("scale_free_space.ratio", "scale_free_space.ratio")]
    for cause in causes:
        names.append(cause.symbol)
        kinds.append("axis")
        key = (f"scale_free_space.causes.{cause.name}.nodes" if len(causes) == 1
               else f"scale_free_space.pairs (the nodes of {cause.name})")
        keys.append((key,) * 2)
    for n in model.nuisance:
        names.append(n.symbol)
        kinds.append("axis")
        keys.append((f"the given {n.symbol} (its sd, {NUISANCE_RANGE:g} sd searched)",) * 2)
    flags = bound_flags(obj, theta, names, kinds, keys)
    params = model.parameters(np.asarray(theta, dtype=float))
    for f in flags:
        f["value"] = params[f["parameter"]]
        f["neutral"] = False
    for k, cause in enumerate(causes):
        f = flags[2 + k]
        end = cause.nodes[0] if f["side"] == "lower" else cause.nodes[-1]
        f["neutral"] = bool(f["edge"] == "window" and end == cause.neutral)
    return {f["parameter"]: f for f in flags}


def fit_intervals(space: RaySpace, data: dict, theta, *, noise_dof: float = math.inf,
                  level: float = 0.95):
    """Profile-likelihood intervals of the fitted parameters (X1d, X1h and the cause's).

    See :func:`skinsuction.identify.profile_intervals`: chi2 with each probe's
    noise sd, evaluated on a grid of (log10 X1d, log10 X1h/X1d, cause axis)
    around ``theta``.  A cause parameter whose interval reaches its neutral end
    (X2d = 0, lambda0 = 1) is consistent with the baseline there: that end is
    not open.

    Parameters
    ----------
    space : RaySpace
        The fitted model's ray space.
    data : dict
        ``{probe_mm: FitData}``, as fitted.
    theta : array_like
        The fit (:attr:`Fit.theta`).
    noise_dof : float
        Degrees of freedom of the noise estimate (inf: known).
    level : float
        Confidence level of each interval.

    Returns
    -------
    LikelihoodIntervals
    """
    model = ModelCurves(space, data)
    params = {"X1d": lambda t: 10.0 ** t[:, 0], "X1h": lambda t: 10.0 ** (t[:, 0] + t[:, 1])}
    for k, cause in enumerate(model.causes):
        params[cause.symbol] = (lambda t, k=k, cause=cause: np.asarray(
            cause.value(cause.from_axis(t[:, 2 + k]), 10.0 ** t[:, 0]), dtype=float))
    for j, n in enumerate(model.nuisance):
        params[n.symbol] = (lambda t, j=j, n=n:
                            np.asarray(n.thickness(t[:, model.n_model + j]), dtype=float))
    ci = profile_intervals(_Objective(model).residuals, theta, model.lower, model.upper,
                           params, level=level, noise_dof=noise_dof)
    for cause in model.causes:
        if cause.neutral != cause.lower:
            continue
        iv = ci.parameters[cause.symbol]
        if iv.lower_open and iv.lower <= cause.value(cause.neutral, 1.0) + 1e-12:
            ci.parameters[cause.symbol] = replace(iv, lower_open=False)
    return ci
