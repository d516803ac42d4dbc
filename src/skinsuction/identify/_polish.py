"""A local polish of a window-focusing estimate: bounded least squares from it.

The window focusing (paper section 2.4) stops when the best E of two successive
iterations agree to C.  In a long, flat valley of the cost (the 6 mm probe alone
trades X1d against X1h, and the scale-free space spans decades of both) its
window can collapse on a stretch of the valley away from the minimum: at the
paper's test point the 6 mm runs stop at E = 0.6-1.6 µm, X1d 50 % too high, while
E at the truth is 0.006 µm.  A trust-region least-squares from the estimate,
within the bounds of the space, walks down the valley to the minimum.

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

import numpy as np

__all__ = ["polish"]


def polish(objective, theta0, max_nfev: int = 200) -> np.ndarray:
    """The best fit near ``theta0`` within ``objective.lower/upper``.

    ``objective`` needs ``residuals(candidates) -> (N, r)`` and
    ``__call__(candidates) -> cost``.  Non-finite residuals (a candidate without
    a curve) count as large.  Returns ``theta0`` (clipped to the bounds) if the
    polish does not lower the cost.
    """
    from scipy.optimize import least_squares

    lo, hi = np.asarray(objective.lower, float), np.asarray(objective.upper, float)
    x0 = np.clip(np.asarray(theta0, dtype=float).reshape(-1), lo, hi)

    def residuals(t):
        r = np.asarray(objective.residuals(t[None, :])[0], dtype=float)
        return np.where(np.isfinite(r), r, 1e3)

    try:
        sol = least_squares(residuals, x0, bounds=(lo, hi), method="trf",
                            x_scale=np.maximum(hi - lo, 1e-12) * 0.05, diff_step=1e-7,
                            xtol=1e-12, ftol=1e-12, gtol=1e-12, max_nfev=max_nfev)
    except ValueError:
        return x0
    c0, c1 = (float(objective(np.asarray(t)[None, :])[0]) for t in (x0, sol.x))
    return sol.x if c1 <= c0 else x0
