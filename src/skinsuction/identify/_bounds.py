"""Is a fitted parameter at the edge of what was simulated?

A fit whose best value sits on a bound of the simulated space may want a value
outside it: the estimate is then a bound, not a measurement.  Two kinds of edge:

* the **window** of the space: the parameter is within 1 % of a bound
  (relative for moduli and ratios, in log; 1 % of the axis width for other
  coordinates);
* the **coverage frontier**: inside the window, but a 1 % step outward leaves
  the usable space (an FE run stopped there, so the candidate has no curve).

Both are reported, never silently passed over.

Examples
--------
>>> import numpy as np
>>> class Box:  # cost 0 inside [0, 1] x [0, 1], inf beyond 0.5 in the 2nd
...     lower, upper = np.zeros(2), np.ones(2)
...     def __call__(self, t):
...         return np.where(np.asarray(t)[:, 1] > 0.5, np.inf, 0.0)
>>> flags = bound_flags(Box(), [0.3, 0.5], ["a", "b"], ["axis", "axis"])
>>> [(f["parameter"], f["at_bound"], f["side"], f["edge"]) for f in flags]
[('a', False, None, None), ('b', True, 'upper', 'coverage')]
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["bound_flags", "BOUND_FRACTION"]

#: Relative distance (1 %) within which a parameter counts as at a bound.
BOUND_FRACTION = 0.01


def _steps(theta, lower, upper, kinds):
    """The 1 % step of each coordinate in theta units."""
    out = np.empty(theta.size)
    for i, kind in enumerate(kinds):
        if kind == "log":  # theta is log10 of a modulus or a ratio
            out[i] = math.log10(1.0 + BOUND_FRACTION)
        elif kind == "relative":  # theta is the modulus itself
            out[i] = BOUND_FRACTION * max(abs(theta[i]), 1e-300)
        elif kind == "axis":
            out[i] = BOUND_FRACTION * (upper[i] - lower[i])
        else:
            raise ValueError(f"unknown coordinate kind {kind!r}")
    return out


def bound_flags(objective, theta, names, kinds, config_keys=None) -> list[dict]:
    """One flag per parameter of ``theta``: at a bound of the space or not.

    Parameters
    ----------
    objective : callable
        ``objective(candidates (N, d)) -> cost (N,)`` with ``lower``, ``upper``;
        +inf where the space has no curve.
    theta : array_like (d,)
        The fitted candidate.
    names : list of str
        Parameter names for the report.
    kinds : list of {"log", "relative", "axis"}
        How a 1 % step is measured on each coordinate (see the module docstring).
    config_keys : list of (str, str) or None
        Configuration keys that widen the lower and the upper end of each axis.

    Returns
    -------
    list of dict
        ``parameter, at_bound, side ("lower" | "upper" | None), edge ("window" |
        "coverage" | None), bound (theta units), config_key``.
    """
    theta = np.asarray(theta, dtype=float).reshape(-1)
    lower = np.asarray(objective.lower, dtype=float)
    upper = np.asarray(objective.upper, dtype=float)
    steps = _steps(theta, lower, upper, kinds)
    probes = []
    for i in range(theta.size):
        for sign in (-1.0, 1.0):
            t = theta.copy()
            t[i] += sign * steps[i]
            probes.append(t)
    with np.errstate(all="ignore"):
        costs = np.asarray(objective(np.array(probes)), dtype=float)
    out = []
    for i, name in enumerate(names):
        side = edge = None
        for k, (s, bound) in enumerate((("lower", lower[i]), ("upper", upper[i]))):
            if abs(theta[i] - bound) <= steps[i] * (1 + 1e-9):
                side, edge = s, "window"
                break
            if not math.isfinite(costs[2 * i + k]):
                side, edge = s, "coverage"
                break
        key = None
        if side is not None and config_keys is not None:
            key = config_keys[i][0 if side == "lower" else 1]
        out.append({"parameter": name, "at_bound": side is not None, "side": side,
                    "edge": edge,
                    "bound": (float(lower[i] if side == "lower" else upper[i])
                              if edge == "window" else None),
                    "config_key": key})
    return out
