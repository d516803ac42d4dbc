"""Along a ray's load: cubic Lagrange on log M in log q, and on M in q at the onset.

A ray is M at the loads ``q_0 = 0 < q_1 < ... < q_n`` of its FE run.  Above
``q_1`` the interpolant is the cubic Lagrange polynomial of log M in log q: a
curve that bends from bending (M ~ q) to membrane stretching (M ~ q^(1/3)) is
nearly straight in those coordinates, and the onset loads double from node to
node.  Cubic Lagrange of M in q, the first scheme, missed direct FE runs by up to
0.78 % there (a 0.6 mm dermis over a soft hypodermis under the 8 mm probe), log M
in log q by 0.21 % (``docs/scale_free_space.md``, the load axis).  Below
``q_1`` (log q has no node at 0) it stays cubic Lagrange of M in q through
``q_0 .. q_3``, with M(0) = 0.

Both are exact at the nodes.  A node of weight exactly 0 is ignored (a ray that
stopped there), and next to where a ray stopped the stencil shifts back while it
still holds the load's cell, so the interpolant never reads past a ray's reach.
"""

from __future__ import annotations

import numpy as np

from ._lagrange import LagrangeAxis

__all__ = ["LoadAxis"]


class LoadAxis:
    """The interpolation of rays along their load.

    Parameters
    ----------
    loads : array_like, shape (n + 1,)
        The loads of the rays' FE runs, ascending from 0, at least 4.

    Examples
    --------
    >>> q = np.array([0.0, 1.0, 2.0, 4.0, 8.0, 16.0])
    >>> axis = LoadAxis(q)
    >>> log_m = np.log(q[1:] ** 0.5)[None, :]          # one ray, M = sqrt(q)
    >>> w = axis.weights(np.array([[3.0, 0.5]]))
    >>> np.round(axis.read(log_m, w), 6).tolist()  # sqrt(3) exactly; below q_1, cubic in q
    [[1.732051, 0.596891]]
    """

    def __init__(self, loads):
        q = np.asarray(loads, dtype=float).reshape(-1)
        if q.size < 4 or q[0] != 0.0 or not np.all(np.diff(q) > 0):
            raise ValueError("loads must ascend from 0 with at least 4 values")
        self.loads = q
        self.first = float(q[1])
        self._log = LagrangeAxis(np.log(q[1:]))
        self._onset = LagrangeAxis(q[:4])
        # each cell of log q has one stencil, so the interpolant there is one cubic in
        # (log q - its left node): its monomial coefficients are a fixed 4 x 4 map of the
        # stencil's log M (the inverse Vandermonde matrix of the stencil's nodes)
        nodes, m = self._log.nodes, self._log.m
        self._cell_start = self._log._start_of[np.arange(1, nodes.size)]
        self._to_monomials = np.stack([
            np.linalg.inv(np.vander(nodes[s:s + m] - nodes[k], m, increasing=True))
            for k, s in enumerate(self._cell_start)])

    def weights(self, q) -> dict:
        """The stencils and weights of the loads ``q`` (any shape, >= 0; NaN is outside).

        Returns
        -------
        dict
            ``shape``, ``high`` (the flat indices read in log q), their ``start``
            (columns of log M, i.e. load index - 1) and ``w``, ``log_q``, the
            ``low`` ones with ``w_low`` (over q_0 .. q_3), and ``loads``: how
            many loads (from q_0) the stencils read, for
            :meth:`skinsuction.space.RayInterpolant.combined_rays`.
        """
        q = np.asarray(q, dtype=float)
        flat = q.reshape(-1)
        high = np.flatnonzero(flat >= self.first)
        low = np.flatnonzero(~(flat >= self.first))  # NaN too: its weights are NaN
        log_q = np.log(flat[high])
        start, w = self._log.weights(log_q)
        _, w_low = self._onset.weights(flat[low])
        loads = int(start.max()) + self._log.m + 1 if start.size else 4
        return {"shape": q.shape, "high": high, "start": start, "w": w, "log_q": log_q,
                "low": low, "w_low": w_low, "loads": max(loads, 4)}

    def loads_for(self, q) -> int:
        """How many loads (from q_0) reading ``q`` needs: ``weights(q)["loads"]``."""
        top = np.nanmax(q, initial=0.0) if np.size(q) else 0.0
        if not top >= self.first:
            return 4
        r = int(np.searchsorted(self._log.nodes, np.log(top), side="right"))
        return max(int(self._log._start_of[r]) + self._log.m + 1, 4)

    def evaluate(self, log_m, q) -> np.ndarray:
        """``read(log_m, weights(q))``, row by row as one piecewise cubic in log q.

        The same interpolant as :meth:`read` (to rounding): each row's cubic of a cell
        is built once, then read at every load of the row in that cell, instead of a
        stencil's weights per load. A load whose cell holds a stopped ray's NaN, and
        the loads below ``q_1``, are read by :meth:`read` and its rules.

        Parameters
        ----------
        log_m : ndarray, shape (N, L)
            As in :meth:`read`.
        q : ndarray, shape (N, u)
            Loads, row i read off row i of ``log_m``.

        Examples
        --------
        >>> q = np.array([0.0, 1.0, 2.0, 4.0, 8.0, 16.0])
        >>> axis = LoadAxis(q)
        >>> log_m = np.log(q[1:] ** 0.5)[None, :]
        >>> x = np.array([[3.0, 0.5, 16.0, 20.0]])
        >>> np.allclose(axis.evaluate(log_m, x), axis.read(log_m, axis.weights(x)),
        ...             equal_nan=True)
        True
        """
        return self.evaluate_at(log_m, self.stencils_of(q, log_m.shape))

    def stencils_of(self, q, shape) -> dict:
        """The loads' cells and offsets, for :meth:`evaluate_at` on any rays of ``shape``.

        Rays read at the same loads (the model's curve and its thickness brackets at the
        same X1d) share this part of :meth:`evaluate`, about half its cost.

        Parameters
        ----------
        q : ndarray, shape (N, u)
        shape : (int, int)
            ``log_m.shape`` of the rays to be read, (N, L).

        Returns
        -------
        dict
        """
        q = np.asarray(q, dtype=float)
        n_rows, width = shape
        per_row = q.size // max(n_rows, 1)
        nodes, m = self._log.nodes, self._log.m
        cells = min(len(self._cell_start), width - m + 1)
        flat = q.reshape(-1)
        with np.errstate(divide="ignore", invalid="ignore"):
            x = np.log(flat)
        cell = np.searchsorted(nodes, x, side="right") - 1
        cell[x == nodes[-1]] -= 1  # the last node closes the last cell
        here = np.flatnonzero((cell >= 0) & (cell < cells) & (flat >= self.first))
        by_rules = np.ones(q.size, bool)  # the loads left to read()'s rules
        by_rules[here] = False
        by_rules[x > nodes[-1]] = False  # beyond the last load: NaN
        c, rows = cell[here], here // per_row
        return {"shape": q.shape, "width": width, "per_row": per_row, "cells": cells,
                "flat": flat, "x": x, "here": here, "by_rules": by_rules, "c": c,
                "rows": rows, "at": (rows * cells + c) * m, "dx": x[here] - nodes[c]}

    def evaluate_at(self, log_m, st: dict) -> np.ndarray:
        """:meth:`evaluate` of ``log_m`` at the loads of :meth:`stencils_of`."""
        if log_m.shape[1] != st["width"]:
            raise ValueError(f"rays of {log_m.shape[1]} loads, stencils of {st['width']}")
        nodes, m, cells = self._log.nodes, self._log.m, st["cells"]
        here, x, c, rows, dx = st["here"], st["x"], st["c"], st["rows"], st["dx"]
        out = np.full(st["flat"].size, np.nan)
        by_rules = st["by_rules"].copy()
        if here.size:
            stencils = self._cell_start[:cells, None] + np.arange(m)
            coef = np.einsum("kij,nkj->nki", self._to_monomials[:cells], log_m[:, stencils])
            at = st["at"]
            f = coef.reshape(-1)
            v = f.take(at + m - 1)
            for k in range(m - 2, -1, -1):
                v = v * dx + f.take(at + k)
            out[here] = np.exp(v)
            # a stopped ray's NaN in the stencil: read()'s rules, unless it is at an end
            # of a cell the load lies strictly inside (then every stencil fails: NaN)
            bad = np.flatnonzero(np.isnan(v))
            rb, cb = rows[bad], c[bad]
            sure = ((dx[bad] > 0.0) & (x[here[bad]] < nodes[cb + 1])
                    & (np.isnan(log_m[rb, cb]) | np.isnan(log_m[rb, cb + 1])))
            by_rules[here[bad[~sure]]] = True
        rest = np.flatnonzero(by_rules)
        if rest.size:
            out[rest] = self._read_flat(log_m, rest // st["per_row"], st["flat"][rest])
        return out.reshape(st["shape"])

    def read(self, log_m, weights) -> np.ndarray:
        """M at the loads of ``weights`` off the rays ``log_m``.

        Parameters
        ----------
        log_m : ndarray, shape (N, L)
            log M of N rays at the loads q_1 .. q_L (L >= 3), NaN where a ray
            stopped; row i is read by the loads of row i of ``q`` (``q`` of shape
            (N, u)).
        weights : dict
            :meth:`weights` of ``q``.

        Returns
        -------
        ndarray, shape of ``q``
            Deflections; NaN outside the loads or beyond a ray's reach.
        """
        shape = weights["shape"]
        n_rays = log_m.shape[0]
        per_ray = int(np.prod(shape)) // max(n_rays, 1)
        rows = np.repeat(np.arange(n_rays), per_ray)
        return self._read_weighted(log_m, rows, weights).reshape(shape)

    def _read_flat(self, log_m, rows, q) -> np.ndarray:
        """M at the loads ``q`` (flat), load i off the ray ``rows[i]``."""
        return self._read_weighted(log_m, rows, self.weights(q))

    def _read_weighted(self, log_m, rows, weights) -> np.ndarray:
        width = log_m.shape[1]
        flat = log_m.reshape(-1)
        row0 = rows * width
        out = np.empty(rows.size)
        hi = weights["high"]
        if hi.size:
            out[hi] = np.exp(self._read_log(flat, row0[hi], weights["start"], weights["w"],
                                            weights["log_q"]))
        lo = weights["low"]
        if lo.size:
            # M at q_0 = 0 .. q_3; a node of weight 0 is ignored (a ray stopped there)
            w = weights["w_low"]
            nodes = np.zeros_like(w)
            nodes[:, 1:] = np.exp(flat.take(row0[lo, None] + np.arange(3)))
            out[lo] = np.where(w == 0.0, 0.0, w * nodes).sum(axis=1)
        return out

    def _read_log(self, flat, row0, start, w, log_q):
        """log M off the flat rays, stencil by stencil, the stopped rays' rules applied."""
        m = self._log.m
        first = row0 + start
        # one 1-D gather per stencil node: faster than one (k, m) gather
        w_by_node = w.T
        vals = w_by_node[0] * flat.take(first)
        for k in range(1, m):
            vals += w_by_node[k] * flat.take(first + k)
        redo = np.flatnonzero(np.isnan(vals))
        redo = redo[(w[redo] == 0.0).any(axis=1)]
        if redo.size:
            nodes = flat.take(first[redo, None] + np.arange(m))
            vals[redo] = np.where(w[redo] == 0.0, 0.0, w[redo] * nodes).sum(axis=1)
        hole = np.flatnonzero(np.isnan(vals) & ~np.isnan(w[:, 0]))
        if hole.size:
            xh = log_q[hole]
            cell = np.searchsorted(self._log.nodes, xh, side="right") - 1
            for shift in (1, 2):
                s = start[hole] - shift
                ok = (s >= 0) & (s + m - 2 >= cell)
                if not ok.any():
                    break
                ws = self._log.weights_at(xh[ok], s[ok])
                ids = row0[hole[ok], None] + s[ok, None] + np.arange(m)
                alt = np.where(ws == 0.0, 0.0, ws * flat.take(ids)).sum(axis=1)
                fill = hole[ok]
                vals[fill] = np.where(np.isnan(vals[fill]), alt, vals[fill])
        return vals
