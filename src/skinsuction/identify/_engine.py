"""The fitting engine: one search, one polish, one set of intervals under every fit.

Every fit of skinsuction (the ramp identification, the time-curve fit, the fit of
each model of the diagnosis) is the same three steps on an *objective*:

1. :func:`focus`: window focusing (paper section 2.4) from the box of the space,
   N = 1000 uniform samples, the Nb = 20 best shrink the box, stop when
   ``|E_{j-1} - E_j| < C``; repeated from seeds ``SeedSequence(seed).spawn(R)``
   (:func:`identify_repeated`);
2. :func:`polish`: bounded least squares (trust region) from a point
   (:func:`polish_run` reports the start, the end point and both costs);
3. intervals: profile likelihood on the space
   (:func:`~skinsuction.identify.profile_intervals`), or the Laplace
   approximation where a profile costs too much (the time curves,
   :func:`~skinsuction.identify.laplace_intervals`).

:func:`repeated_fit` composes 1 and 2: the runs and any given starts (e.g. a
nested model's fit), the best candidates polished, a typed :class:`FitResult`.

The objective
-------------
A callable from parameter vectors ``(n, k)`` to costs ``(n,)`` (+inf where the
space has no curve) with the attributes of :class:`Objective`: ``lower``,
``upper`` (the box searched when no bounds are given), ``error(cost)`` (E, eq. 7,
what the window focusing's stop compares) and ``error_unit``, ``residuals``
(``(n, k) -> (n, r)``, half their squared norm is the cost; for the polish and
the intervals) and, if the polish is asked to use it, ``jacobian``.  The ramps'
objectives (:func:`~skinsuction.identify.single_objective`, weighted, ratio) are
such callables; a fit in units of the noise (the diagnosis, the time curves)
subclasses :class:`Chi2Objective` and gives its residual blocks.

Who uses what
-------------
* the ramp identification (:func:`skinsuction.identify.measured_fit.identify_data`):
  :func:`repeated_fit` with ``estimate="median", skip_failed=False``: 100 runs,
  the median of their estimates (the paper's statistic), polished, then
  :func:`profile_intervals`;
* the time curves (:func:`skinsuction.identify.fit_time_model`):
  :func:`repeated_fit` with the looser stop ``TIME_WF`` and the polish
  ``TIME_POLISH`` (its own Jacobian), then :func:`laplace_intervals`;
* the diagnosis (:func:`skinsuction.diagnose.fit_model`): :func:`repeated_fit`
  with the paper's settings, then :func:`profile_intervals`.

Examples
--------
A straight line through noisy points, in units of the noise (sd 0.1):

>>> import numpy as np
>>> x = np.linspace(0, 1, 20)
>>> y = 1.0 + 2.0 * x + np.random.default_rng(0).normal(0, 0.1, x.size)
>>> class Line(Chi2Objective):
...     def blocks(self, t):
...         return [(y - t[:, :1] - t[:, 1:] * x) / 0.1]
>>> fit = repeated_fit(Line([-5, -5], [5, 5], x.size), repeats=2, seed=0)
>>> exact = np.polyfit(x, y, 1)[::-1]
>>> bool(np.allclose(fit.x, exact, atol=1e-6)), fit.polished, len(fit.runs.results)
(True, 2, 2)
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from ._intervals import interval_threshold, misfit_scale, profile_intervals
from ._objectives import Chi2Objective
from ._polish import POLISH, Polished, polish, polish_run
from ._window_focusing import (
    IdentificationError,
    RepeatedIdentification,
    WindowFocusingResult,
    focus,
    identify_repeated,
    repeated_runs,
    window_focusing,
    window_of,
)

__all__ = ["Objective", "Chi2Objective", "focus", "window_focusing", "identify_repeated",
           "RepeatedIdentification", "polish", "polish_run", "Polished", "POLISH",
           "repeated_fit", "FitResult", "profile_intervals", "interval_threshold",
           "misfit_scale", "IdentificationError", "WindowFocusingResult"]


class Objective(Protocol):
    """What the engine asks of an objective (see the module docstring)."""

    lower: np.ndarray
    upper: np.ndarray
    error_unit: str

    def __call__(self, candidates: np.ndarray) -> np.ndarray:
        """Costs ``(n,)`` of the candidates ``(n, k)``; +inf where there is no curve."""

    def error(self, cost: float) -> float:
        """E (eq. 7) of a cost, in ``error_unit``."""

    def residuals(self, candidates: np.ndarray) -> np.ndarray:
        """``(n, r)`` residuals whose half squared norm is the cost."""


@dataclass(frozen=True)
class FitResult:
    """What :func:`repeated_fit` found.

    Attributes
    ----------
    x : ndarray (k,)
        The estimate.
    cost : float
        Its cost.
    start : ndarray (k,)
        The estimate before the polish: the best candidate (or the runs' median).
    runs : RepeatedIdentification
        The window focusing runs that finished (a failed run is left out).
    candidates : ndarray (m, k)
        The runs' estimates, then the usable starts (``estimate="best"``).
    costs : ndarray (m,)
        Their costs.
    polished : int
        Polishes the solver ran.
    repeats : int
        Runs asked for.
    settings : dict
        The window focusing's settings.
    """

    x: np.ndarray
    cost: float
    start: np.ndarray
    runs: RepeatedIdentification
    candidates: np.ndarray
    costs: np.ndarray
    polished: int
    repeats: int
    settings: dict = field(default_factory=dict)

    def summary(self) -> dict:
        """JSON-able: the runs (``chi2_runs``: 2 x each run's cost, chi^2 for a
        :class:`Chi2Objective`), the polishes and the settings."""
        n = len(self.runs.results)
        return {"runs": n, "iterations": [int(r.iterations) for r in self.runs.results],
                "converged": [bool(r.converged) for r in self.runs.results],
                "chi2_runs": [2 * float(c) for c in self.costs[:n]],
                "polished": self.polished, "settings": self.settings,
                "repeats": self.repeats}


def _median_fit(objective, lower, upper, runs, repeats, starts, polish_best, polish_options,
                settings, error_message) -> FitResult:
    """The ramps' rule: the polish of the coordinate-wise median of the runs."""
    if starts:
        raise ValueError("estimate='median' takes no starts")
    if not runs:
        raise IdentificationError(error_message)
    rep = RepeatedIdentification.of(runs)
    start = np.median(rep.estimates, axis=0)
    costs = np.array([float(objective(np.asarray(c)[None, :])[0]) for c in rep.estimates])
    if polish_best > 0:
        p = polish_run(objective, start, (lower, upper), **polish_options)
        x, cost = (p.x, p.cost) if p.cost <= p.start_cost else (p.start, p.start_cost)
        return FitResult(x, cost, start, rep, rep.estimates, costs, int(p.ran), repeats, settings)
    cost = float(objective(start[None, :])[0])
    return FitResult(start, cost, start, rep, rep.estimates, costs, 0, repeats, settings)


def repeated_fit(objective, bounds=None, *, repeats: int = 2, seed=0, starts=(),
                 focus_options: dict | None = None, polish_best: int = 2,
                 polish_options: dict | None = None, estimate: str = "best",
                 skip_failed: bool = True,
                 error_message: str = "no parameters of the space reproduce the curves "
                                      "(every candidate has an infinite cost)") -> FitResult:
    """Window focusing runs from seeds and the given starts, the best polished.

    Parameters
    ----------
    objective : callable
        See :class:`Objective`.
    bounds : (lower, upper), optional
        The box searched and polished in; default the objective's.
    repeats : int
        Window focusing runs, >= 0, seeds ``SeedSequence(seed).spawn(repeats)``.
    seed : int or numpy.random.SeedSequence
    starts : sequence of array_like (k,)
        More candidates (e.g. a nested model's fit); one of another size or of
        infinite cost is left out.
    focus_options : dict, optional
        Options of :func:`focus` (``n_samples``, ``n_best``, ``tolerance``,
        ``max_iter``); recorded in the result's ``settings``.
    polish_best : int
        Polish the ``polish_best`` candidates of lowest cost (0: no polish); a
        polished end point replaces the estimate if its cost is lower.
    polish_options : dict, optional
        Settings of :func:`polish_run` (default :data:`POLISH`).
    estimate : {"best", "median"}
        ``"best"``: the candidate of lowest cost, then its polish (the diagnosis,
        the time curves); ``"median"``: the coordinate-wise median of the runs'
        estimates, replaced by its polish unless the polish raises the cost (the
        ramp identification: the paper's statistic).
    skip_failed : bool
        Leave out a run that finds no finite cost (else its
        :class:`IdentificationError` is raised).
    error_message : str
        The :class:`IdentificationError`'s message when no candidate is left.

    Returns
    -------
    FitResult

    Raises
    ------
    IdentificationError
        No candidate with a finite cost (or a failed run, ``skip_failed=False``).
    """
    if estimate not in ("best", "median"):
        raise ValueError(f"estimate must be 'best' or 'median', not {estimate!r}")
    lower, upper = window_of(objective, bounds)
    settings = dict(focus_options or {})
    polish_options = dict(polish_options or {})
    runs = repeated_runs(objective, (lower, upper), repeats, seed, settings, skip_failed)
    if estimate == "median":
        return _median_fit(objective, lower, upper, runs, int(repeats), starts, polish_best,
                           polish_options, settings, error_message)
    cands = [r.estimate for r in runs]
    for s in starts:
        s = np.asarray(s, dtype=float)
        if s.size == lower.size and np.isfinite(objective(s[None, :])[0]):
            cands.append(s)
    if not cands:
        raise IdentificationError(error_message)
    costs = [float(objective(np.asarray(c)[None, :])[0]) for c in cands]
    order = np.argsort(costs)
    start = best = np.asarray(cands[order[0]], dtype=float)
    best_cost = costs[order[0]]
    polished = 0
    for i in order[:max(int(polish_best), 0)]:
        p = polish_run(objective, cands[i], (lower, upper), **polish_options)
        if not p.ran:
            continue
        polished += 1
        if p.cost < best_cost:
            best, best_cost = p.x, p.cost
    return FitResult(best, best_cost, start, RepeatedIdentification.of(runs), np.array(cands),
                     np.array(costs), polished, int(repeats), settings)
