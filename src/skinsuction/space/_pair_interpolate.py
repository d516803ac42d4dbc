"""A pair of causes off its nodes: the first cause's interpolant on each slice of the
second, then cubic Lagrange in the second cause's axis on log M, then along the load
as for one cause (:class:`PairRayInterpolant`); :func:`interpolant` picks the
interpolant of any ray space."""

from __future__ import annotations

import numpy as np

from ._lagrange import LagrangeAxis
from ._pairs import PairRaySpace
from ._ray_interpolate import RayInterpolant, _alternative_starts
from ._ray_space import RaySpace

__all__ = ["PairRayInterpolant", "interpolant"]


class PairRayInterpolant(RayInterpolant):
    """M(X1d, X1h, c1, c2, p) of one probe at fixed measured pressures.

    ``theta`` is ``(log10 X1d, log10 r, u1, u2)``; the first cause's
    interpolant on each slice of the second, combined by cubic Lagrange in
    ``u2`` on log M (no extrapolation), then read along the load as for one
    cause (:class:`RayInterpolant`).
    """

    def __init__(self, space: PairRaySpace, probe_mm: float, pressure_mbar):
        n2 = len(space.second.nodes)
        self._slices = [RayInterpolant(space.slice_second(j), probe_mm, pressure_mbar)
                        for j in range(n2)]
        super().__init__(space.slice_second(0), probe_mm, pressure_mbar)
        self.space = space
        self._axis_2 = LagrangeAxis(space.second.axis_nodes)
        self.d = 4

    @property
    def lower(self) -> np.ndarray:
        return np.append(self._slices[0].lower, self.space.second.axis_nodes[0])

    @property
    def upper(self) -> np.ndarray:
        return np.append(self._slices[0].upper, self.space.second.axis_nodes[-1])

    def combined_logs(self, theta, loads=None) -> np.ndarray:
        theta = np.asarray(theta, dtype=float)
        n = theta.shape[0]
        start, w = self._axis_2.weights(theta[:, 3])
        outside = np.isnan(w[:, 0])
        m = self._axis_2.m
        # only the slices a stencil can reach (a search narrows to a few of them)
        inside = start[~outside] if (~outside).any() else start[:1]
        lo, hi = max(0, int(inside.min()) - 2), min(len(self._slices), int(inside.max()) + m + 2)
        width = self._g.shape[-1] if loads is None else loads - 1
        logs = np.full((len(self._slices), n, width), np.nan)
        for j in range(lo, hi):
            logs[j] = self._slices[j].combined_logs(theta[:, :3], loads)
        g = _combine_rows(logs, start, w, np.arange(n), m)
        bad = np.flatnonzero(np.isnan(g).any(axis=1) & ~outside)
        if bad.size:
            # a slice whose ray stopped early: the other stencils holding the cell
            sub = g[bad]
            for alt in _alternative_starts(self._axis_2, theta[bad, 3], start[bad])[1:]:
                hole = np.isnan(sub)
                if not hole.any():
                    break
                wa = self._axis_2.weights_at(theta[bad, 3], alt)
                sub = np.where(hole, _combine_rows(logs, alt, wa, bad, m), sub)
            g[bad] = sub
        g[outside] = np.nan
        return g


def _combine_rows(logs, start, w, rows, m):
    """Lagrange sum over the second cause's slices, ignoring a slice of weight 0."""
    stencil = logs[start[:, None] + np.arange(m), rows[:, None]]
    zeroed = np.where((w == 0.0)[:, :, None], 0.0, stencil)
    return np.einsum("nk,nkp->np", w, zeroed)


def interpolant(space: RaySpace, probe_mm: float, pressure_mbar) -> RayInterpolant:
    """The interpolant of any ray space: one cause or none, or a pair."""
    if isinstance(space, PairRaySpace):
        return PairRayInterpolant(space, probe_mm, pressure_mbar)
    return RayInterpolant(space, probe_mm, pressure_mbar)
