"""Fit a model (neo-Hookean or one cause) on its ray space: window focusing, then polish.

The parameters searched are ``theta = (log10 X1d, log10 r[, c])`` with
``r = X1h / X1d`` and ``u`` the axis coordinate of the cause (its ray
coordinate on the cause's scale, :meth:`Cause.to_axis`; see :mod:`._rays`): the window focusing of the paper (section 2.4, N = 1000,
Nb = 20) samples uniformly in the box of the space, which in logarithms covers
decades of moduli evenly.  The cost is ``chi^2 / 2`` with the noise level of
each point, so both probes weigh by their noise.  The best of ``repeats``
window focusing runs (independent seeds) is then polished by a bounded
least-squares (trust region), so that the chi^2 that the BIC compares is the
minimum and not the stochastic stop of the window focusing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.optimize import least_squares

from skinsuction.identify import (
    IdentificationError,
    bound_flags,
    profile_intervals,
    window_focusing,
)
from skinsuction.identify.measured_fit import decorrelate, space_error_direction

from skinsuction.space import RayInterpolant, RaySpace

__all__ = ["FitData", "Fit", "ModelCurves", "fit_model", "fit_bounds", "fit_intervals",
           "with_space_error", "PAPER_WF"]

#: Window focusing settings of the paper (section 2.4); C in units of sqrt(chi^2/n).
PAPER_WF = {"n_samples": 1000, "n_best": 20, "tolerance": 1e-6, "max_iter": 200}


@dataclass(frozen=True)
class FitData:
    """The points fitted for one probe: pressures (mbar), deflections (mm), noise sd (µm)."""

    probe_mm: float
    pressure_mbar: np.ndarray
    deflection_mm: np.ndarray
    sigma_um: float
    curve_ids: tuple = ()
    #: (unit direction, gamma) of the space's correlated error along the curve
    #: (:func:`with_space_error`), or None: independent points
    space_error: tuple | None = None

    @property
    def n(self) -> int:
        return int(self.pressure_mbar.size)

    def whiten(self, z: np.ndarray) -> np.ndarray:
        """Residuals in units of sigma (N, n) -> independent unit-variance ones."""
        if self.space_error is None:
            return z
        return decorrelate(z, *self.space_error)


def with_space_error(data: dict, x1d_mpa: float) -> dict:
    """``data`` ({probe: FitData}) with the space's correlated error of each probe.

    The error of the scale-free space against direct FE runs is smooth along a
    curve and grows with the load p / X1d (soft skin under the 6 mm probe); it
    enters each probe's likelihood as one rank-one covariance term, as in the
    identification's intervals (:func:`skinsuction.identify.measured_fit.space_error_direction`,
    measured by ``benchmarks/space_error_profile.py``).  The load of a point is taken
    at ``x1d_mpa`` (the baseline's X1d): every model of the diagnosis then weighs
    the points alike.
    """
    out = {}
    for p, d in data.items():
        a, gamma = space_error_direction(p, d.pressure_mbar, d.deflection_mm, x1d_mpa,
                                         np.full(d.n, 1e-3 * d.sigma_um))
        out[p] = replace(d, space_error=None if a is None else (a, gamma))
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
        self.interp = {p: RayInterpolant(space, p, d.pressure_mbar) for p, d in data.items()}
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
        model = {p: f(own) for p, f in self.interp.items()}
        out = dict(model)
        for j, brackets in enumerate(self._brackets):
            delta = theta[:, self.n_model + j][:, None]
            n = self.nuisance[j]
            # a cause's own brackets are read at its coordinate too; brackets centred
            # on this model's own space have its curve as their centre
            at = own if n.center.cause is not None else own[:, :2]
            for p, (center, minus, plus) in brackets.items():
                m0 = model[p] if n.center is self.space else center(at)
                lo, hi = minus(at), plus(at)
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
        cause = self.space.cause
        if cause is not None:
            out[cause.symbol] = float(cause.value(cause.from_axis(theta[2]), x1d))
        for j, n in enumerate(self.nuisance):
            out[n.symbol] = float(n.thickness(theta[self.n_model + j]))
        return out


def nested_start(base_theta, cause) -> np.ndarray:
    """A cause's theta at its neutral value from the neo-Hookean fit's theta.

    The cause's coordinate goes after (X1d, X1h/X1d) and before any thickness
    nuisance, as :class:`ModelCurves` orders them; the cause's model then fits
    at least as well as the neo-Hookean one.

    >>> from skinsuction.space import default_registry
    >>> nested_start([-1.4, -2.0, 0.3], default_registry()["pre_tension"])
    array([-1.4, -2. ,  1. ,  0.3])
    """
    t = np.asarray(base_theta, dtype=float)
    return np.concatenate([t[:2], [cause.to_axis(cause.neutral)], t[2:]])


#: Search range of a thickness nuisance, in sd units either side of the given value.
NUISANCE_RANGE = 3.0


class _Objective:
    """chi^2 / 2 for window focusing (vectorised) and residuals for least squares."""

    error_unit = "1"

    def __init__(self, model: ModelCurves):
        self.model = model
        self.lower, self.upper = model.lower, model.upper
        self.n = sum(d.n for d in model.data.values())

    def __call__(self, theta) -> np.ndarray:
        chi2 = 0.0
        for p, m in self.model(theta).items():
            d = self.model.data[p]
            r = d.whiten((d.deflection_mm[None, :] - m) * (1e3 / d.sigma_um))
            chi2 = chi2 + np.einsum("nt,nt->n", r, r)
        chi2 = chi2 + self.model.prior(theta)
        cost = 0.5 * np.asarray(chi2, dtype=float)
        cost[~np.isfinite(cost)] = np.inf
        return cost

    def error(self, cost) -> float:
        return math.sqrt(2.0 * cost / self.n)  # RMS of the normalised residuals

    def residuals(self, theta) -> np.ndarray:
        out = []
        for p, m in self.model(np.asarray(theta, dtype=float)[None, :]).items():
            d = self.model.data[p]
            out.append(d.whiten((d.deflection_mm - m[None, 0]) * (1e3 / d.sigma_um))[0])
        out.append(np.asarray(theta, dtype=float)[self.model.n_model:])  # the prior
        r = np.concatenate(out)
        return np.where(np.isfinite(r), r, 1e6)


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
    """A :class:`Fit` at a given theta (chi^2, E, residuals)."""
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
    """Fit the model of ``space`` to ``data`` ({probe: FitData}).

    ``repeats`` window focusing runs with seeds spawned from ``seed``; the best
    one (and any of ``starts``, thetas e.g. of a nested model) is polished by
    bounded least squares.  Raises :class:`IdentificationError` if no candidate
    of the space gives a finite cost.
    """
    model = ModelCurves(space, data)
    obj = _Objective(model)
    wf = {**PAPER_WF, **(window_focusing_options or {})}
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
        raise IdentificationError(f"{space.name}: no parameters of the space reproduce the "
                                  "measured pressures (all candidates non-converged)")
    costs = [float(obj(np.asarray(c)[None, :])[0]) for c in cands]
    order = np.argsort(costs)
    best, best_cost = np.asarray(cands[order[0]]), costs[order[0]]
    n_polished = 0
    if polish:
        lo, hi = obj.lower, obj.upper
        # the best window-focusing result, and the best start if it is a different point
        for i in order[: 2]:
            x0 = np.clip(np.asarray(cands[i], dtype=float), lo, hi)
            try:
                sol = least_squares(obj.residuals, x0, bounds=(lo, hi), method="trf",
                                    x_scale=np.maximum(hi - lo, 1e-12) * 0.05,
                                    diff_step=1e-7, xtol=1e-12, ftol=1e-12, gtol=1e-12,
                                    max_nfev=200)
            except ValueError:
                continue
            n_polished += 1
            c = float(obj(sol.x[None, :])[0])
            if c < best_cost:
                best, best_cost = sol.x, c
    info = {"runs": len(runs), "iterations": [int(r.iterations) for r in runs],
            "converged": [bool(r.converged) for r in runs],
            "chi2_runs": [2 * float(c) for c in costs[: len(runs)]],
            "polished": n_polished, "settings": wf, "repeats": int(repeats)}
    return evaluate_fit(model, best, space.name, info)


def fit_bounds(space: RaySpace, data: dict, theta) -> dict:
    """``{parameter: flag}``: which fitted parameters sit at an edge of the space.

    See :func:`skinsuction.identify.bound_flags`; each flag names the
    configuration key that widens the space there.  A cause's parameter at its
    neutral end (e.g. X2d = 0) is the baseline model, not an edge: its flag has
    ``neutral: True``.
    """
    model = ModelCurves(space, data)
    obj = _Objective(model)
    spec, cause = space.spec, space.cause
    raised = model.lower[0] > math.log10(spec.x1d_range[0]) + 1e-12
    x1d_lo = ("scale_free_space.load.max (the largest measured pressure over load.max sets "
              "the lowest X1d)" if raised else "scale_free_space.x1d_mpa.min")
    names, kinds = ["X1d", "X1h"], ["log", "log"]
    keys = [(x1d_lo, "scale_free_space.x1d_mpa.max"),
            ("scale_free_space.ratio", "scale_free_space.ratio")]
    if cause is not None:
        names.append(cause.symbol)
        kinds.append("axis")
        keys.append((f"scale_free_space.causes.{cause.name}.nodes",) * 2)
    for n in model.nuisance:
        names.append(n.symbol)
        kinds.append("axis")
        keys.append((f"the given {n.symbol} (its sd, {NUISANCE_RANGE:g} sd searched)",) * 2)
    flags = bound_flags(obj, theta, names, kinds, keys)
    params = model.parameters(np.asarray(theta, dtype=float))
    for f in flags:
        f["value"] = params[f["parameter"]]
        f["neutral"] = False
    if cause is not None:
        f = flags[2]
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
    """
    model = ModelCurves(space, data)
    cause = space.cause

    def residuals(t):
        curves = model(t)
        parts = [model.data[p].whiten((model.data[p].deflection_mm[None, :] - c)
                                      * (1e3 / model.data[p].sigma_um))
                 for p, c in curves.items()]
        parts.append(np.asarray(t, dtype=float)[:, model.n_model:])  # the thickness prior
        return np.concatenate(parts, axis=1)

    params = {"X1d": lambda t: 10.0 ** t[:, 0], "X1h": lambda t: 10.0 ** (t[:, 0] + t[:, 1])}
    if cause is not None:
        params[cause.symbol] = lambda t: np.asarray(
            cause.value(cause.from_axis(t[:, 2]), 10.0 ** t[:, 0]), dtype=float)
    for j, n in enumerate(model.nuisance):
        params[n.symbol] = (lambda t, j=j, n=n:
                            np.asarray(n.thickness(t[:, model.n_model + j]), dtype=float))
    ci = profile_intervals(residuals, theta, model.lower, model.upper, params, level=level,
                           noise_dof=noise_dof)
    if cause is not None and cause.neutral == cause.lower:
        iv = ci.parameters[cause.symbol]
        if iv.lower_open and iv.lower <= cause.value(cause.neutral, 1.0) + 1e-12:
            from dataclasses import replace

            ci.parameters[cause.symbol] = replace(iv, lower_open=False)
    return ci
