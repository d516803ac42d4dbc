"""Classical optimisers on the same interpolated simulated space, for comparison.

Both work on an objective of :mod:`skinsuction.identify` (so on exactly the same cost
as the window focusing) inside the bounds of the space, and return a
:class:`BaselineResult`.  ``n_evaluations`` counts candidates evaluated (one
candidate = one interpolated curve set), as in the window focusing result.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from scipy import optimize

__all__ = ["BaselineResult", "least_squares_from_random_starts", "differential_evolution_fit"]

#: Residual (in the objective's unit) given to least_squares where the
#: interpolated space is NaN (non-converged region): a large finite penalty,
#: since least_squares refuses non-finite residuals.
NAN_RESIDUAL = 1e3


@dataclass(frozen=True)
class BaselineResult:
    """Outcome of a baseline optimiser.

    Attributes
    ----------
    estimate : ndarray (2,)
        (X1d, X1h) in MPa.
    cost : float
    E : float
        Correlation error (eq. 7) in the objective's unit.
    success : bool
        The optimiser's own success flag (for random starts: of the best start).
    n_evaluations : int
    seconds : float
    details : dict
    """

    estimate: np.ndarray
    cost: float
    E: float
    success: bool
    n_evaluations: int
    seconds: float
    details: dict = field(default_factory=dict, repr=False)


class _Counted:
    """Wraps an objective and counts the candidates it evaluates."""

    def __init__(self, objective):
        self.objective = objective
        self.count = 0

    def residuals(self, x):
        self.count += 1
        r = self.objective.residuals(np.asarray(x, dtype=float).reshape(1, 2))[0]
        return np.where(np.isfinite(r), r, NAN_RESIDUAL)

    def costs(self, x):  # x: (2, S) as scipy's vectorised DE passes it
        x = np.atleast_2d(np.asarray(x, dtype=float).T)
        self.count += x.shape[0]
        return self.objective(x)


def least_squares_from_random_starts(
    objective, *, seed, n_starts: int = 10, bounds=None, **least_squares_options
) -> BaselineResult:
    """``scipy.optimize.least_squares`` (trust-region reflective) from random starts.

    The starts are uniform in the bounds (default: the space bounds); the best
    end point (lowest cost) is returned.  The variables are scaled by the
    window size (``x_scale``), as X1d and X1h differ by two orders of magnitude.

    Examples
    --------
    >>> from skinsuction.identify import analytic_surrogate_space, single_objective
    >>> from skinsuction.space import evaluate
    >>> s6 = analytic_surrogate_space(6.0)
    >>> obj = single_objective(s6, (s6.pressure_mbar, evaluate(s6, [[0.0055, 0.00041]])[0]))
    >>> r = least_squares_from_random_starts(obj, seed=0, n_starts=3)
    >>> r.estimate.round(5).tolist()
    [0.0055, 0.00041]
    """
    t0 = time.perf_counter()
    lower, upper = (objective.lower, objective.upper) if bounds is None else bounds
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    rng = np.random.default_rng(seed)
    counted = _Counted(objective)
    options = {"method": "trf", "x_scale": upper - lower, **least_squares_options}
    best, runs = None, []
    for x0 in lower + (upper - lower) * rng.random((int(n_starts), 2)):
        res = optimize.least_squares(counted.residuals, x0, bounds=(lower, upper), **options)
        runs.append({"x0": x0.tolist(), "x": res.x.tolist(), "cost": float(res.cost),
                     "status": int(res.status), "nfev": int(res.nfev)})
        if best is None or res.cost < best.cost:
            best = res
    j = float(objective(best.x.reshape(1, 2))[0])
    return BaselineResult(
        estimate=best.x.copy(),
        cost=j,
        E=float(objective.error(j)),
        success=bool(best.success),
        n_evaluations=counted.count,
        seconds=time.perf_counter() - t0,
        details={"starts": runs},
    )


def differential_evolution_fit(
    objective, *, seed, bounds=None, **de_options
) -> BaselineResult:
    """``scipy.optimize.differential_evolution`` on the cost, vectorised.

    Defaults: ``polish=False`` (the polishing L-BFGS-B step does not cope with
    +inf costs of non-converged regions), ``tol=1e-8`` and ``atol=1e-14``
    (population spread of the cost, so in mm^2 for the single and weighted
    objectives; an absolute floor is needed as the cost of an exact fit is 0);
    any option of scipy's function can be passed.

    Examples
    --------
    >>> from skinsuction.identify import analytic_surrogate_space, single_objective
    >>> from skinsuction.space import evaluate
    >>> s6 = analytic_surrogate_space(6.0)
    >>> obj = single_objective(s6, (s6.pressure_mbar, evaluate(s6, [[0.0055, 0.00041]])[0]))
    >>> r = differential_evolution_fit(obj, seed=0)
    >>> r.estimate.round(5).tolist()
    [0.0055, 0.00041]
    """
    t0 = time.perf_counter()
    lower, upper = (objective.lower, objective.upper) if bounds is None else bounds
    counted = _Counted(objective)
    options = {"polish": False, "tol": 1e-8, "atol": 1e-14, "updating": "deferred",
               **de_options}
    res = optimize.differential_evolution(
        counted.costs,
        list(zip(np.asarray(lower, float), np.asarray(upper, float))),
        rng=np.random.default_rng(seed),
        vectorized=True,
        **options,
    )
    j = float(objective(res.x.reshape(1, 2))[0])
    return BaselineResult(
        estimate=np.asarray(res.x, dtype=float).copy(),
        cost=j,
        E=float(objective.error(j)),
        success=bool(res.success),
        n_evaluations=counted.count,
        seconds=time.perf_counter() - t0,
        details={"nit": int(res.nit), "message": str(res.message)},
    )
