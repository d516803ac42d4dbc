"""Local cubic Lagrange interpolation on one axis: the weights of every layout.

On each axis the interpolant is the cubic Lagrange polynomial through the 4
nodes around the point: the two nodes of its cell and one more on each side
(shifted inwards at the ends of the axis; with fewer than 4 nodes, the
polynomial through them all).  The grid layout uses it in X1d, X1h and p
(:mod:`._interpolate`), the scale-free layout across rays and along their load
(:mod:`._ray_interpolate`), the spaces of one measurement across apertures
(:mod:`._geometry`).  The weights are exactly 1 and 0 at the nodes (the
denominators are the numerators' formula evaluated at the nodes, with the same
rounding), so the interpolant is exact there.
"""

from __future__ import annotations

import numpy as np

__all__ = ["LagrangeAxis"]


def _numerators(d: np.ndarray) -> np.ndarray:
    """Lagrange numerators ``prod_{j != k} d_j`` for each k, rows of ``d`` (N, m)."""
    m = d.shape[1]
    if m == 4:  # by pairs: 8 products instead of 12
        d0, d1, d2, d3 = d.T
        p01, p23 = d0 * d1, d2 * d3
        return np.stack([d1 * p23, d0 * p23, p01 * d3, p01 * d2], axis=1)
    return np.stack([np.prod(np.delete(d, k, axis=1), axis=1) for k in range(m)], axis=1)


def _cubic_weights(x, start, columns) -> np.ndarray:
    """Cubic Lagrange weights (N, 4) of the stencils ``start``, as `_numerators` then
    division by the denominators, in the same operations (bit for bit), by columns."""
    d0, d1, d2, d3 = (x - c.take(start) for c in columns[:4])
    p01, p23 = d0 * d1, d2 * d3
    w = np.empty((4, x.size))
    for k, (a, b) in enumerate(((d1, p23), (d0, p23), (p01, d3), (p01, d2))):
        np.multiply(a, b, out=w[k])
        np.divide(w[k], columns[4 + k].take(start), out=w[k])
    return w.T


class LagrangeAxis:
    """Local cubic Lagrange weights on one grid axis.

    Parameters
    ----------
    nodes : array_like, shape (n,)
        Strictly increasing grid nodes.  With fewer than 4 nodes the stencil has
        ``n`` nodes (linear for 2, quadratic for 3).

    Examples
    --------
    >>> ax = LagrangeAxis([0.0, 1.0, 2.0, 3.0, 4.0])
    >>> start, w = ax.weights([1.0, 2.5])
    >>> start.tolist()
    [0, 1]
    >>> (w.round(4) + 0.0).tolist()
    [[0.0, 1.0, 0.0, 0.0], [-0.0625, 0.5625, 0.5625, -0.0625]]
    """

    def __init__(self, nodes):
        nodes = np.asarray(nodes, dtype=float)
        if nodes.ndim != 1 or nodes.size < 2 or not np.all(np.diff(nodes) > 0):
            raise ValueError("nodes must be 1-D, strictly increasing, with >= 2 values")
        self.nodes = nodes
        self.m = min(4, nodes.size)
        self.n_starts = nodes.size - self.m + 1
        offsets = np.arange(self.m)
        self._offsets = offsets
        stencils = nodes[np.arange(self.n_starts)[:, None] + offsets]  # (n_starts, m)
        # denominators: the numerator formula at x = node k (same rounding, so
        # the weights are exactly 1 and 0 at the nodes)
        denom = np.empty((self.n_starts, self.m))
        for k in range(self.m):
            denom[:, k] = _numerators(stencils[:, k : k + 1] - stencils)[:, k]
        # one gather per call: stencil nodes and denominators side by side
        self._table = np.concatenate([stencils, denom], axis=1)  # (n_starts, 2m)
        # searchsorted(side="right") r in 0..n  ->  stencil start
        # (cell r - 1, stencil from cell - 1, shifted inwards at the ends)
        r = np.arange(nodes.size + 1)
        self._start_of = np.clip(r - 1 - (self.m // 2 - 1), 0, self.n_starts - 1)
        # the same table by columns: for many points, gathering 1-D columns and
        # writing weights row by row of a (m, N) array is twice as fast
        self._columns = [np.ascontiguousarray(c) for c in self._table.T]

    def weights(self, x):
        """Stencil start index and Lagrange weights for the points ``x``.

        Parameters
        ----------
        x : array_like, shape (N,)
            Points on the axis (flattened).

        Returns
        -------
        start : ndarray of int, shape (N,)
            Index of the first stencil node; the stencil is ``start + arange(m)``.
        weights : ndarray, shape (N, m)
            Weights of the stencil nodes; NaN rows for points outside the nodes.
        """
        x = np.asarray(x, dtype=float).reshape(-1)
        r = np.searchsorted(self.nodes, x, side="right")
        start = self._start_of[r]
        w = self.weights_at(x, start)
        outside = (r == 0) | ~(x <= self.nodes[-1])  # NaN is outside too
        if outside.any():
            w[outside] = np.nan
        return start, w

    def weights_at(self, x, start) -> np.ndarray:
        """Weights of the points ``x`` on the stencils starting at ``start``
        (centred or not; no check that x lies inside them).

        Parameters
        ----------
        x : array_like, shape (N,)
            Points on the axis (flattened).
        start : ndarray of int, shape (N,)
            First node of each point's stencil, in ``0 .. n - m``.

        Returns
        -------
        ndarray, shape (N, m)
        """
        x = np.asarray(x, dtype=float).reshape(-1)
        if self.m == 4:
            return _cubic_weights(x, start, self._columns)
        table = self._table[start]  # (N, 2m)
        w = _numerators(x[:, None] - table[:, :self.m])
        w /= table[:, self.m:]
        return w
