"""The engine's local step: bounded least squares from a point (the polish).

The window focusing (paper section 2.4) stops when the best E of two successive
iterations agree to C.  In a long, flat valley of the cost (the 6 mm probe alone
trades X1d against X1h, and the scale-free space spans decades of both) its
window can collapse on a stretch of the valley away from the minimum: at the
paper's test point the 6 mm runs stop at E = 0.6-1.6 µm, X1d 50 % too high, while
E at the truth is 0.006 µm.  A trust-region least-squares from the estimate,
within the bounds of the space, walks down the valley to the minimum.

One solver and one set of settings (:data:`POLISH`) for every fit; a fit changes
them by keyword (the time curves: :data:`skinsuction.identify._time_fit.TIME_POLISH`,
their own Jacobian and a looser tolerance).  :func:`polish_run` reports the start,
the solver's end point and both costs; :func:`polish` returns the better point.

Examples
--------
>>> import numpy as np
>>> class Valley:  # residuals vanish at (0.3, 0.7); cost grows slowly along x0 + x1
...     lower, upper = np.zeros(2), np.ones(2)
...     def residuals(self, t):
...         t = np.atleast_2d(t)
...         return np.stack([10 * (t[:, 0] - t[:, 1] + 0.4), 0.01 * (t[:, 0] - 0.3)], 1)
...     def __call__(self, t):
...         return 0.5 * (self.residuals(t) ** 2).sum(axis=1)
>>> polish(Valley(), [0.5, 0.9]).round(6).tolist()
[0.3, 0.7]
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._window_focusing import window_of

__all__ = ["POLISH", "Polished", "polish", "polish_run", "forward_jacobian"]

#: The polish's settings (the ramps and the diagnosis): at most ``max_nfev`` residual
#: evaluations, ``tol`` for the solver's xtol, ftol and gtol, forward differences of
#: ``diff_step`` (relative, all k steps in one call of the residuals: a call costs
#: about as much for 1 candidate as for k + 1) unless ``jacobian`` (the objective's
#: own ``jacobian``), non-finite residuals (a candidate without a curve) replaced by
#: ``nonfinite``.
POLISH = {"max_nfev": 200, "tol": 1e-12, "diff_step": 1e-7, "jacobian": False,
          "nonfinite": 1e3}

#: The trust region's scale of each coordinate, as a fraction of the box's width.
X_SCALE = 0.05


@dataclass(frozen=True)
class Polished:
    """What one polish did.

    Attributes
    ----------
    start : ndarray (k,)
        The start, clipped to the bounds.
    start_cost : float
        Its cost.
    x : ndarray (k,)
        The solver's end point (the start if the solver refused it).
    cost : float
        Its cost.
    ran : bool
        False if the solver refused the start (then ``x`` is the start).
    nfev : int
        Residual evaluations of the solver.
    """

    start: np.ndarray
    start_cost: float
    x: np.ndarray
    cost: float
    ran: bool
    nfev: int = 0

    @property
    def best(self) -> np.ndarray:
        """The end point if its cost is not higher than the start's, else the start."""
        return self.x if self.cost <= self.start_cost else self.start


def polish_run(objective, x0, bounds=None, **settings) -> Polished:
    """Bounded least squares (trust region) from ``x0``: the engine's local step.

    Parameters
    ----------
    objective : callable
        ``objective(candidates (N, k)) -> cost (N,)`` with ``residuals(candidates
        (N, k)) -> (N, r)`` whose half squared norm is the cost, ``lower`` and
        ``upper`` when ``bounds`` is None, and ``jacobian(x (k,)) -> (r, k)`` when
        ``settings["jacobian"]``.
    x0 : array_like (k,)
        The start; clipped to the bounds.
    bounds : (lower, upper), optional
        Default the objective's ``lower``, ``upper``.
    **settings
        Override :data:`POLISH` (``max_nfev``, ``tol``, ``diff_step``, ``jacobian``,
        ``nonfinite``).

    Returns
    -------
    Polished
    """
    from scipy.optimize import least_squares

    unknown = set(settings) - set(POLISH)
    if unknown:
        raise TypeError(f"unknown polish settings {sorted(unknown)}; known: {sorted(POLISH)}")
    s = {**POLISH, **settings}
    lo, hi = window_of(objective, bounds)
    x0 = np.clip(np.asarray(x0, dtype=float).reshape(-1), lo, hi)
    bad = float(s["nonfinite"])

    def residuals(t):
        r = np.asarray(objective.residuals(t[None, :])[0], dtype=float)
        return np.where(np.isfinite(r), r, bad)

    def forward_differences(t):
        return forward_jacobian(objective.residuals, t, lo, hi, float(s["diff_step"]), bad)

    def cost_of(t):
        return float(objective(np.asarray(t)[None, :])[0])

    tol = float(s["tol"])
    try:
        sol = least_squares(residuals, x0,
                            jac=objective.jacobian if s["jacobian"] else forward_differences,
                            bounds=(lo, hi), method="trf",
                            x_scale=np.maximum(hi - lo, 1e-12) * X_SCALE,
                            diff_step=s["diff_step"], xtol=tol, ftol=tol, gtol=tol,
                            max_nfev=int(s["max_nfev"]))
    except ValueError:  # e.g. the residuals at the start are not finite
        c0 = cost_of(x0)
        return Polished(x0, c0, x0, c0, False)
    c0, c1 = cost_of(x0), cost_of(sol.x)
    return Polished(x0, c0, sol.x, c1, True, int(sol.nfev))


def forward_jacobian(residuals, x, lower, upper, diff_step: float, nonfinite: float = 1e3):
    """The Jacobian of ``residuals`` at ``x`` by forward differences, in one call.

    The steps are scipy's "2-point" ones (``diff_step`` relative, at least
    ``diff_step``; backwards where a step forward would leave the bounds), all
    k of them and ``x`` evaluated together: a call of the space's objectives
    costs about as much for k + 1 candidates as for one.

    Parameters
    ----------
    residuals : callable
        ``(N, k) -> (N, r)``.
    x : ndarray (k,)
    lower, upper : ndarray (k,)
    diff_step : float
    nonfinite : float
        Replaces a residual that is not finite.

    Returns
    -------
    ndarray (r, k)

    Examples
    --------
    >>> f = lambda t: np.stack([t[:, 0] ** 2, t[:, 0] * t[:, 1]], axis=1)
    >>> forward_jacobian(f, np.array([1.0, 2.0]), np.zeros(2), np.array([2.0, 2.0]),
    ...                  1e-7).round(5).tolist()  # at the upper bound x1 steps back
    [[2.0, -0.0], [2.0, 1.0]]
    """
    x = np.asarray(x, dtype=float)
    h = diff_step * np.maximum(1.0, np.abs(x)) * np.where(x >= 0, 1.0, -1.0)
    h = np.where((x + h > upper) | (x + h < lower), -h, h)
    h = (x + h) - x  # the step actually taken
    r = np.asarray(residuals(np.vstack([x, x + np.diag(h)])), dtype=float)
    r = np.where(np.isfinite(r), r, nonfinite)
    return (r[1:] - r[0]).T / h


def polish(objective, x0, bounds=None, **settings) -> np.ndarray:
    """The best fit near ``x0`` within the bounds: :func:`polish_run`'s better point.

    Parameters
    ----------
    objective : callable
        As for :func:`polish_run`: costs, ``residuals`` and the bounds.
    x0 : array_like (k,)
        The start (e.g. the median of the window focusing runs).
    bounds : (lower, upper), optional
        Default the objective's ``lower``, ``upper``.
    **settings
        Override :data:`POLISH`.

    Returns
    -------
    ndarray (k,)
        The solver's end point, or ``x0`` (clipped to the bounds) if the polish
        does not lower the cost or the solver refused the start.
    """
    return polish_run(objective, x0, bounds, **settings).best
