"""The window focusing stochastic algorithm (paper section 2.4, eqs. 5-8).

1. The window starts at the bounds of the simulated space.
2. Iteration j draws N candidates uniformly in the window (eq. 5).
3. The cost of all candidates is evaluated (one vectorised call) and sorted.
4. The new window is the min/max of the Nb best candidates (eq. 6).

The iterations stop when ``|E_{j-1} - E_j| < C`` where ``E_j`` is the
correlation error (eq. 7) of the best candidate of iteration j; the estimate is
that best candidate of the last iteration.  (There is no E_0, so at least two
iterations run.)  Candidates with cost +inf (non-converged parts of the space)
are never among the Nb best unless fewer than Nb candidates are finite, in which
case only the finite ones define the window; if none is finite the
identification fails with :class:`IdentificationError`.

:func:`focus` is this run as a step of the fitting engine (:mod:`._engine`): the
window and the random generator are its arguments.  :func:`window_focusing` is the
same run under the paper's name, the seed a keyword; :func:`identify_repeated`
repeats it from independent seeds (paper: 100 runs).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

__all__ = [
    "IdentificationError",
    "IterationState",
    "WindowFocusingResult",
    "RepeatedIdentification",
    "focus",
    "window_focusing",
    "identify_repeated",
    "repeated_runs",
    "samples_for",
    "window_of",
]


class IdentificationError(RuntimeError):
    """The window focusing cannot go on (e.g. every candidate has cost +inf)."""


def _n_smallest(costs: np.ndarray, k: int) -> np.ndarray:
    """Indices of the k smallest costs, sorted by increasing cost."""
    if k < costs.size:
        part = np.argpartition(costs, k - 1)[:k]
    else:
        part = np.arange(costs.size)
    return part[np.argsort(costs[part], kind="stable")]


def samples_for(rho: float, e: float) -> int:
    """Eq. 8: number of samples N = ln(1 - rho) / ln(1 - e), rounded up.

    N uniform samples reach the global minimum with accuracy ``e`` (fraction of
    the window) with probability ``rho``.

    Parameters
    ----------
    rho : float
        Probability, in (0, 1).
    e : float
        Accuracy as a fraction of the window, in (0, 1).

    Returns
    -------
    int

    Examples
    --------
    >>> samples_for(0.99, 0.01)
    459
    >>> samples_for(0.999, 0.01)
    688
    """
    rho, e = float(rho), float(e)
    if not (0.0 < rho < 1.0 and 0.0 < e < 1.0):
        raise ValueError(f"rho and e must lie in (0, 1), got rho={rho}, e={e}")
    return int(math.ceil(math.log1p(-rho) / math.log1p(-e)))


@dataclass(frozen=True)
class IterationState:
    """What one iteration saw; passed to the ``callback`` of :func:`window_focusing`."""

    iteration: int
    lower: np.ndarray
    upper: np.ndarray
    samples: np.ndarray  # (N, d)
    costs: np.ndarray  # (N,)
    best: np.ndarray  # indices of the Nb best samples, best first
    E: float


@dataclass(frozen=True)
class WindowFocusingResult:
    """Outcome of one window focusing identification.

    Attributes
    ----------
    estimate : ndarray (d,)
        The best candidate of the last iteration: (X1d, X1h) in MPa for the
        paper's objectives.
    E, E_unit : float, str
        Correlation error (eq. 7) of the estimate and its unit ("µm", or "1"
        for the dimensionless ratio objective).
    cost : float
        Cost (eq. 4, 10 or 11-12) of the estimate.
    iterations : int
    windows : list of (lower, upper)
        ``windows[0]`` is the initial window (space bounds); ``windows[j]`` the
        window computed by eq. 6 at iteration j.
    E_history : ndarray (iterations,)
        E of the best candidate of each iteration.
    n_evaluations : int
        Number of candidates evaluated (N x iterations).
    converged : bool
        False if ``max_iter`` was hit before ``|E_{j-1} - E_j| < C``.
    seconds : float
    """

    estimate: np.ndarray
    E: float
    E_unit: str
    cost: float
    iterations: int
    windows: list = field(repr=False)
    E_history: np.ndarray = field(repr=False)
    n_evaluations: int = 0
    converged: bool = False
    seconds: float = 0.0

    @property
    def x1d(self) -> float:
        return float(self.estimate[0])

    @property
    def x1h(self) -> float:
        return float(self.estimate[1])

    @property
    def E_um(self) -> float:
        """E in µm (NaN for a dimensionless objective)."""
        return float(self.E) if self.E_unit == "µm" else math.nan


def window_of(objective, bounds=None) -> tuple:
    """The box ``(lower, upper)`` searched: ``bounds`` or the objective's own.

    Parameters
    ----------
    objective : object
        With ``lower`` and ``upper`` (length k) when ``bounds`` is None.
    bounds : (lower, upper), optional
        The box; each of length k.

    Returns
    -------
    lower, upper : ndarray (k,)
        Float copies.

    Raises
    ------
    ValueError
        Bounds of different or no dimension, not finite, or ``lower > upper``.

    Examples
    --------
    >>> window_of(None, ([0, 1], [2, 3]))
    (array([0., 1.]), array([2., 3.]))
    """
    if bounds is None:
        lower, upper = objective.lower, objective.upper
    else:
        lower, upper = bounds
    lower = np.array(lower, dtype=float).reshape(-1)
    upper = np.array(upper, dtype=float).reshape(-1)
    if lower.size == 0 or lower.shape != upper.shape:
        raise ValueError(f"window bounds of different or no dimension: {lower}, {upper}")
    if not (np.all(np.isfinite(lower)) and np.all(np.isfinite(upper)) and np.all(lower <= upper)):
        raise ValueError(f"invalid window bounds lower={lower}, upper={upper}")
    return lower, upper


def _iteration(objective, rng, lower, upper, n_samples: int, n_best: int, j: int):
    """Iteration j: N samples in the window (eq. 5), their costs, the Nb best with a
    finite cost, best first."""
    samples = lower + (upper - lower) * rng.random((n_samples, lower.size))  # eq. 5
    costs = np.asarray(objective(samples), dtype=float)
    best = _n_smallest(costs, n_best)
    best = best[np.isfinite(costs[best])]
    if best.size == 0:
        raise IdentificationError(
            f"iteration {j}: all {n_samples} candidates in the window "
            f"{lower.tolist()}..{upper.tolist()} have an infinite cost "
            "(non-converged part of the simulated space?)"
        )
    return samples, costs, best


def focus(
    objective,
    bounds=None,
    rng=None,
    *,
    n_samples: int = 1000,
    n_best: int = 20,
    tolerance: float = 1e-6,
    max_iter: int = 200,
    callback: Callable[[IterationState], None] | None = None,
) -> WindowFocusingResult:
    """One window focusing run (paper section 2.4): the engine's search step.

    Parameters
    ----------
    objective : callable
        ``objective(candidates (N, k)) -> cost (N,)``, +inf where there is no
        curve; with ``error(cost)`` (E, eq. 7) and ``error_unit``, and ``lower``,
        ``upper`` when ``bounds`` is None (the protocol of :mod:`._engine`).  The
        paper's problems have k = 2, (X1d, X1h); any k >= 1 works.
    bounds : (lower, upper), optional
        The first window; default the objective's ``lower``, ``upper`` (the
        bounds of the simulated space).
    rng : int, numpy.random.SeedSequence or numpy.random.Generator
        Source of the random samples (``numpy.random.default_rng(rng)``); required,
        so every run is reproducible.
    n_samples : int
        N, candidates per iteration (paper: 1000; see :func:`samples_for`).
    n_best : int
        Nb, candidates that define the next window (paper: 20).
    tolerance : float
        C, stop when ``|E_{j-1} - E_j| < C``, in the unit of E (paper: 1e-6 µm).
    max_iter : int
        Guard; the result has ``converged=False`` if it is reached.
    callback : callable, optional
        Called with an :class:`IterationState` after each iteration.

    Returns
    -------
    WindowFocusingResult

    Raises
    ------
    IdentificationError
        Every candidate of an iteration has an infinite cost.

    Examples
    --------
    >>> import numpy as np
    >>> class Bowl:  # cost and E: squared distance to (0.3, 0.6) in the unit box
    ...     lower, upper, error_unit = np.zeros(2), np.ones(2), "1"
    ...     def __call__(self, t):
    ...         return ((t - [0.3, 0.6]) ** 2).sum(axis=1)
    ...     def error(self, cost):
    ...         return cost
    >>> r = focus(Bowl(), None, np.random.default_rng(0), tolerance=1e-12)
    >>> r.converged, r.estimate.round(4).tolist()
    (True, [0.3, 0.6])
    """
    if rng is None:
        raise TypeError("focus needs a seed or a random generator (rng): every run is "
                        "reproducible")
    n_samples, n_best, max_iter = int(n_samples), int(n_best), int(max_iter)
    if not 1 <= n_best <= n_samples:
        raise ValueError(f"need 1 <= n_best <= n_samples, got {n_best} and {n_samples}")
    if max_iter < 1 or not tolerance >= 0:
        raise ValueError("max_iter must be >= 1 and tolerance >= 0")
    t0 = time.perf_counter()
    rng = np.random.default_rng(rng)
    lower, upper = window_of(objective, bounds)
    windows = [(lower, upper)]
    e_history = []
    converged = False
    for j in range(1, max_iter + 1):
        samples, costs, best = _iteration(objective, rng, lower, upper, n_samples, n_best, j)
        x_best, j_best = samples[best[0]], float(costs[best[0]])
        e_j = float(objective.error(j_best))
        e_history.append(e_j)
        lower, upper = samples[best].min(axis=0), samples[best].max(axis=0)  # eq. 6
        windows.append((lower, upper))
        if callback is not None:
            callback(IterationState(j, *windows[-2], samples, costs, best, e_j))
        if j > 1 and abs(e_history[-2] - e_j) < tolerance:
            converged = True
            break
    return WindowFocusingResult(
        estimate=x_best.copy(),
        E=e_j,
        E_unit=objective.error_unit,
        cost=j_best,
        iterations=j,
        windows=windows,
        E_history=np.array(e_history),
        n_evaluations=j * n_samples,
        converged=converged,
        seconds=time.perf_counter() - t0,
    )


def window_focusing(objective, *, seed, bounds=None, **options) -> WindowFocusingResult:
    """Identify (X1d, X1h) by window focusing (paper section 2.4): :func:`focus`.

    Parameters
    ----------
    objective : callable
        As for :func:`focus` (e.g. :func:`skinsuction.identify.single_objective`).
    seed : int, numpy.random.SeedSequence or numpy.random.Generator
        Source of the random samples; required, so every run is reproducible.
    bounds : (lower, upper), optional
        Initial window; default the bounds of the simulated space.
    **options
        ``n_samples`` (N), ``n_best`` (Nb), ``tolerance`` (C), ``max_iter``,
        ``callback``: see :func:`focus`.

    Returns
    -------
    WindowFocusingResult

    Examples
    --------
    >>> from skinsuction.identify import analytic_surrogate_space, single_objective
    >>> from skinsuction.space import evaluate
    >>> s6 = analytic_surrogate_space(6.0)
    >>> curve = (s6.pressure_mbar, evaluate(s6, [[0.0055, 0.00041]])[0])
    >>> r = window_focusing(single_objective(s6, curve), seed=1)
    >>> r.converged, r.estimate.round(6).tolist()
    (True, [0.0055, 0.00041])
    """
    return focus(objective, bounds, seed, **options)


@dataclass(frozen=True)
class RepeatedIdentification:
    """Many independent window focusing runs on one objective (paper: 100).

    Attributes
    ----------
    estimates : ndarray (R, k)
    E : ndarray (R,)
    iterations : ndarray (R,)
    converged : ndarray of bool (R,)
    results : list of WindowFocusingResult
    """

    estimates: np.ndarray
    E: np.ndarray
    iterations: np.ndarray
    converged: np.ndarray
    results: list = field(repr=False)

    @classmethod
    def of(cls, results: list) -> "RepeatedIdentification":
        """The runs ``results`` (list of :class:`WindowFocusingResult`) as one record."""
        return cls(estimates=np.array([r.estimate for r in results]),
                   E=np.array([r.E for r in results]),
                   iterations=np.array([r.iterations for r in results]),
                   converged=np.array([r.converged for r in results]),
                   results=list(results))

    @property
    def mean(self) -> np.ndarray:
        """Mean of the estimates, (k,)."""
        return self.estimates.mean(axis=0)

    @property
    def std(self) -> np.ndarray:
        """Sample standard deviation (ddof=1; 0 for one repeat)."""
        if len(self.estimates) < 2:
            return np.zeros(self.estimates.shape[1])
        return self.estimates.std(axis=0, ddof=1)

    @property
    def relative_spread(self) -> np.ndarray:
        """std / |mean| for (X1d, X1h)."""
        return self.std / np.abs(self.mean)

    def relative_error(self, truth) -> np.ndarray:
        """(R, 2) relative errors of the estimates with respect to ``truth``."""
        truth = np.asarray(truth, dtype=float)
        return (self.estimates - truth) / truth

    def summary(self) -> dict:
        """Plain numbers for tables and JSON."""
        return {
            "repeats": int(len(self.estimates)),
            "x1d_mean": float(self.mean[0]),
            "x1h_mean": float(self.mean[1]),
            "x1d_std": float(self.std[0]),
            "x1h_std": float(self.std[1]),
            "x1d_min": float(self.estimates[:, 0].min()),
            "x1d_max": float(self.estimates[:, 0].max()),
            "x1h_min": float(self.estimates[:, 1].min()),
            "x1h_max": float(self.estimates[:, 1].max()),
            "E_mean": float(self.E.mean()),
            "iterations_mean": float(self.iterations.mean()),
            "converged_fraction": float(self.converged.mean()),
        }


def repeated_runs(objective, bounds, repeats: int, seed, options: dict,
                  skip_failed: bool = False) -> list:
    """The window focusing runs from ``SeedSequence(seed).spawn(repeats)``, in order.

    Parameters
    ----------
    objective : callable
        See :func:`focus`.
    bounds : (lower, upper) or None
        The first window of every run.
    repeats : int
        Runs, >= 0.
    seed : int or numpy.random.SeedSequence
        The root of the runs' seeds.
    options : dict
        Options of :func:`focus`.
    skip_failed : bool
        Leave out a run that raises :class:`IdentificationError` (else raise it).

    Returns
    -------
    list of WindowFocusingResult
    """
    root = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence(seed)
    runs = []
    for s in root.spawn(int(repeats)):
        try:
            runs.append(focus(objective, bounds, s, **options))
        except IdentificationError:
            if not skip_failed:
                raise
    return runs


def identify_repeated(objective, repeats: int = 100, seed=0, **options) -> RepeatedIdentification:
    """Run :func:`focus` ``repeats`` times with independent seeds.

    Parameters
    ----------
    objective : callable
        See :class:`Objective`.
    repeats : int
        Runs, >= 1 (paper: 100).
    seed : int or numpy.random.SeedSequence
        The runs' seeds are ``SeedSequence(seed).spawn(repeats)``: the whole set is
        reproducible from it.
    **options
        ``bounds`` and the options of :func:`focus` (``n_samples``, ``n_best``,
        ``tolerance``, ``max_iter``, ``callback``).

    Returns
    -------
    RepeatedIdentification

    Raises
    ------
    IdentificationError
        A run finds no candidate with a finite cost.

    Examples
    --------
    >>> from skinsuction.identify import analytic_surrogate_space, single_objective
    >>> from skinsuction.space import evaluate
    >>> s6 = analytic_surrogate_space(6.0)
    >>> curve = (s6.pressure_mbar, evaluate(s6, [[0.0055, 0.00041]])[0])
    >>> rep = identify_repeated(single_objective(s6, curve), repeats=5, seed=0)
    >>> rep.estimates.shape, bool(rep.converged.all())
    ((5, 2), True)
    """
    repeats = int(repeats)
    if repeats < 1:
        raise ValueError("repeats must be >= 1")
    options = dict(options)
    bounds = options.pop("bounds", None)
    return RepeatedIdentification.of(repeated_runs(objective, bounds, repeats, seed, options))
