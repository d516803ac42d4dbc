"""The posterior's mode over the given layer thicknesses, on the lattice the rays resolve.

With both thicknesses given, two probes often trade a thinner dermis against a
thinner hypodermis: -2 log of the posterior is a narrow, bent valley across the
axes, whose floor rises tens of units over a sd across it and a few along it.  A
quadratic through the fits at +-1 sd puts its vertex on a wall (a 0.92 mm dermis
over 0.83 mm, truly 0.79 over 0.85: the vertex at -0.83, +0.63 sd, ten units above
the floor, X1d 7 % low with an interval 5 % wide).  Gauss-Newton on the fits'
residuals (the moduli fitted again at each thickness: variable projection) walks
along the floor.

The rays resolve a thickness to 0.01 mm (:data:`skinsuction.space.THICKNESS_RESOLUTION_MM`),
so the posterior is a staircase on that lattice: the search runs in lattice units,
each residual is that of the nearest lattice point, and the Jacobian is a central
difference over two lattice steps either way.

Examples
--------
>>> import numpy as np
>>> def fit(n):  # steep across (1, -1), shallow along (1, 1); a prior of 10 units sd
...     u, v = (n[0] - n[1] + 10) / 4.0, (n[0] + n[1] + 16) / 30.0
...     return np.array([u, v, n[0] / 10.0, n[1] / 10.0])
>>> mode = posterior_mode(fit, [10.0, 10.0], start=[0, 0], bound=[30, 30])
>>> mode.offset, round(mode.value, 4), mode.fitted < 61 * 61  # as a brute force finds
((-6, 3), 0.7003, True)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["posterior_mode", "PosteriorMode"]


@dataclass(frozen=True)
class PosteriorMode:
    """Where the search ended: ``offset`` the lattice point of least ``-2 log``
    posterior (``value``) among those fitted, ``jacobian`` the residuals' there
    (per lattice unit), ``fitted`` how many lattice points were fitted."""

    offset: tuple
    value: float
    jacobian: np.ndarray | None
    fitted: int

    def valley(self):
        """``(direction, rise per lattice unit squared)``: the Gauss-Newton Hessian's
        softest direction at the mode, or None without a Jacobian."""
        if self.jacobian is None or not np.all(np.isfinite(self.jacobian)):
            return None
        w, v = np.linalg.eigh(self.jacobian.T @ self.jacobian)
        return v[:, 0], float(max(w[0], 0.0))


def posterior_mode(fit, sd_units, start, bound, max_fits: int = 40) -> PosteriorMode:
    """Least squares of ``fit`` over integer lattice offsets of the thicknesses.

    Parameters
    ----------
    fit : callable
        ``fit(offset)`` (a tuple of ints: lattice steps from the given thicknesses)
        returns the residual vector whose squared norm is ``-2 log`` of the posterior
        there (the curves' residuals over the square root of the misfit scale, then
        each thickness's offset in sd), or None where the geometry spaces do not hold
        that geometry.
    sd_units : sequence of float
        Each thickness's sd in lattice units (its prior's scale).
    start : sequence of int
        The lattice point to start from (the best fit so far).
    bound : sequence of int
        The search stays within ``+-bound`` lattice units of the given thicknesses.
    max_fits : int
        The most lattice points fitted.

    Returns
    -------
    PosteriorMode
    """
    from scipy.optimize import least_squares

    bound = np.asarray(bound, dtype=float)
    memo = {}

    def at(n):
        n = tuple(int(v) for v in np.clip(np.round(n), -bound, bound))
        if n not in memo:
            memo[n] = None if len(memo) >= max_fits else fit(n)
        return memo[n]

    x0 = np.clip(np.round(np.asarray(start, dtype=float)), -bound, bound)
    r0 = at(x0)
    if r0 is None:
        return PosteriorMode(tuple(int(v) for v in x0), float("nan"), None, len(memo))
    size, worst = r0.size, np.sqrt(r0 @ r0) + 1e3

    def fun(x):
        r = at(x)
        return r if r is not None else np.full(size, worst / np.sqrt(size))

    def jac(x):
        n, centre, cols = np.round(x), at(x), []
        for i in range(len(n)):
            step = np.zeros(len(n))
            step[i] = 2
            hi, lo = np.clip(n + step, -bound, bound), np.clip(n - step, -bound, bound)
            r_hi, r_lo = at(hi), at(lo)
            if r_hi is None or r_lo is None:  # one-sided at the grid's edge
                hi, r_hi = (n, centre) if r_hi is None else (hi, r_hi)
                lo, r_lo = (n, centre) if r_lo is None else (lo, r_lo)
            width = hi[i] - lo[i]
            cols.append((r_hi - r_lo) / width if width and r_hi is not None
                        and r_lo is not None else np.zeros(size))
        return np.column_stack(cols)

    try:
        least_squares(fun, x0, jac=jac, method="trf", bounds=(-bound - 0.5, bound + 0.5),
                      x_scale=np.maximum(np.asarray(sd_units, dtype=float), 1.0),
                      xtol=1e-3, max_nfev=max_fits)
    except (ValueError, np.linalg.LinAlgError):
        pass  # the search ends where it is; the best point fitted stands
    fitted = {n: r for n, r in memo.items() if r is not None}
    best = min(fitted, key=lambda n: float(fitted[n] @ fitted[n]))
    jacobian = jac(np.asarray(best, dtype=float))
    return PosteriorMode(best, float(fitted[best] @ fitted[best]), jacobian,
                         len([r for r in memo.values() if r is not None]))
