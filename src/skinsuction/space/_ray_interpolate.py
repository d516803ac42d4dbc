"""The scale-free space off its rays: cubic interpolation across rays and along the load.

Across rays, cubic Lagrange in ``log10 r`` (r = X1h/X1d) and in the cause's
axis coordinate, on ``log M``; along the load of a ray, cubic Lagrange on log M
in log q, ``q = p / X1d`` (:class:`skinsuction.space._load_axis.LoadAxis`;
:class:`RayInterpolant`).  The neo-Hookean space of one probe, tabulated for the
identification, is in :mod:`._neo_hookean_slice`.
"""

from __future__ import annotations

import math

import numpy as np

from ._coordinates import reference_pressure
from ._lagrange import LagrangeAxis
from ._load_axis import LoadAxis
from ._ray_space import RaySpace

__all__ = ["RayInterpolant", "read_at_once"]


def _alternative_starts(axis: LagrangeAxis, x, centred):
    """Other stencil starts that still contain the cell of each x: [None, shifts...].

    ``None`` stands for the centred start; a shift that leaves the cell outside the
    stencil falls back to the centred one for that point.
    """
    cell = np.clip(np.searchsorted(axis.nodes, x, side="right") - 1, 0, axis.nodes.size - 2)
    lo = np.maximum(cell + 2 - axis.m, 0)
    hi = np.minimum(cell, axis.n_starts - 1)
    out = [None]
    for shift in (1, -1, 2, -2):
        s = centred + shift
        ok = (s >= lo) & (s <= hi)
        if ok.any():
            out.append(np.where(ok, s, centred))
    return out


class RayInterpolant:
    """M(X1d, X1h, c, p) of one probe at fixed measured pressures, vectorised.

    Parameters
    ----------
    space : RaySpace
    probe_mm : float
    pressure_mbar : array_like (u,)
        Measured pressures (mbar), any protocol.

    Calling it with ``theta (N, d)`` = ``(log10 X1d, log10 r[, u])`` (``u`` the
    cause's axis coordinate, :meth:`Cause.to_axis`) returns the deflections
    (N, u) in mm; NaN outside the space or beyond the reach of a ray.  Any
    pressures >= 0 are allowed: the lowest X1d searched is raised to
    ``p_max / load_max`` (:attr:`lower`).
    """

    def __init__(self, space: RaySpace, probe_mm: float, pressure_mbar):
        self.space = space
        self.probe_mm = float(probe_mm)
        p = np.asarray(pressure_mbar, dtype=float).reshape(-1)
        spec = space.spec
        if p.size == 0 or np.any(p < 0) or not np.all(np.isfinite(p)):
            raise ValueError("pressures must be finite and >= 0 mbar")
        self.pressure_mbar = p
        self.x1d_min = spec.x1d_lower(p.max())
        if self.x1d_min >= spec.x1d_range[1]:
            raise ValueError(
                f"a pressure of {p.max():g} mbar is beyond the reach of the scale-free space: "
                f"p/X1d <= {spec.load_max:g} mbar/MPa and X1d <= {spec.x1d_range[1]:g} MPa "
                f"allow at most {spec.reach_mbar():g} mbar (scale_free_space.load.max, "
                "scale_free_space.x1d_mpa.max)")
        self.x1d_ref = spec.x1d_ref
        rays = space.rays(probe_mm)  # (n_r, n_c, n_p)
        with np.errstate(divide="ignore", invalid="ignore"):
            g = np.log(rays[..., 1:])  # log M at p > 0; M(0) = 0
        g[~np.isfinite(g)] = np.nan  # a zero or negative deflection is unusable
        self._g = g
        self._flat_g = g.reshape(-1, g.shape[-1])  # rows (r, c)
        self._axis_r = LagrangeAxis(np.log10(spec.ratio_nodes))
        self._axis_c = (LagrangeAxis(space.cause.axis_nodes) if space.cause is not None
                        else None)
        self._load = LoadAxis(spec.pressures_mbar)
        self.d = 2 if space.cause is None else 3

    @property
    def lower(self) -> np.ndarray:
        """Lower bounds of theta: log10 X1d (raised by the load reach), log10 r[, u]."""
        s = self.space.spec
        lo = [math.log10(self.x1d_min), math.log10(s.ratio_nodes[0])]
        if self.d == 3:
            lo.append(float(self.space.cause.axis_nodes[0]))
        return np.array(lo)

    @property
    def upper(self) -> np.ndarray:
        """Upper bounds of theta: log10 X1d (the window's), log10 r[, u]."""
        s = self.space.spec
        hi = [math.log10(s.x1d_range[1]), math.log10(s.ratio_nodes[-1])]
        if self.d == 3:
            hi.append(float(self.space.cause.axis_nodes[-1]))
        return np.array(hi)

    def _combine(self, theta, start_r, start_c=None, wr=None, wc=None, loads=None):
        """log M of the candidates' rays with the given stencil starts, (N, loads - 1).

        ``wr``, ``wc``: the weights of these starts, if already known; ``loads``: the
        first loads of the rays only (all by default)."""
        if wr is None:
            wr = self._axis_r.weights_at(theta[:, 1], start_r)
        rows = start_r[:, None] + np.arange(self._axis_r.m)  # rows of the (r, c) table
        w = wr
        if self.d == 3:
            if wc is None:
                wc = self._axis_c.weights_at(theta[:, 2], start_c)
            n_c = self._g.shape[1]
            rows = (rows[:, :, None] * n_c + start_c[:, None, None]
                    + np.arange(self._axis_c.m)).reshape(len(theta), -1)
            w = (wr[:, :, None] * wc[:, None, :]).reshape(len(theta), -1)
        else:
            rows = rows * self._g.shape[1]
        flat_g = self._flat_g if loads is None else self._flat_g[:, :loads - 1]
        stencil = np.take(flat_g, rows, axis=0)  # (N, stencil, loads - 1)
        out = np.einsum("nk,nkp->np", w, stencil)
        # a ray with weight exactly 0 (the candidate sits on a node) is ignored, so a
        # neighbouring ray that stopped early does not spoil a node (NaN * 0 = NaN)
        redo = np.flatnonzero(np.isnan(out).any(axis=1))
        redo = redo[(w[redo] == 0.0).any(axis=1)]
        if redo.size:
            zeroed = np.where((w[redo] == 0.0)[:, :, None], 0.0, stencil[redo])
            out[redo] = np.einsum("nk,nkp->np", w[redo], zeroed)
        return out

    def combined_rays(self, theta, loads=None) -> np.ndarray:
        """The rays at (r, c) of the candidates, on the rays' own pressures: M, 0 at p = 0
        (:meth:`combined_logs`, exponentiated), shape (N, n_p) or (N, loads)."""
        g = self.combined_logs(theta, loads)
        out = np.empty((g.shape[0], g.shape[1] + 1))
        out[:, 0] = 0.0
        np.exp(g, out=out[:, 1:])
        return out

    def combined_logs(self, theta, loads=None) -> np.ndarray:
        """log M of the rays at (r, c) of the candidates, at the rays' loads > 0.

        NaN policy "shift" (as the identification's): where the centred stencil
        holds a ray that stopped early, the other stencils that still contain the
        candidate's cell are tried in turn, pressure by pressure.

        Parameters
        ----------
        theta : array_like, shape (N, d)
            Candidates ``(log10 X1d, log10 r[, u])`` (X1d is not used here).
        loads : int, optional
            Only the first ``loads`` pressures of the FE runs (a search whose
            candidates read the rays no further pays for no more): the same values
            there as with every load.

        Returns
        -------
        ndarray, shape (N, n_p - 1) or (N, loads - 1)
            log M (mm) at the pressures of the FE runs (``spec.pressures_mbar``) but
            0; NaN outside the rays or beyond their reach.
        """
        theta = np.asarray(theta, dtype=float)
        sr, wr = self._axis_r.weights(theta[:, 1])
        outside = np.isnan(wr[:, 0])
        sc = wc = None
        if self.d == 3:
            sc, wc = self._axis_c.weights(theta[:, 2])
            outside |= np.isnan(wc[:, 0])
        g = self._combine(theta, sr, sc, wr, wc, loads)
        g[outside] = np.nan  # no extrapolation
        bad = np.flatnonzero(np.isnan(g).any(axis=1) & ~outside)
        if bad.size:
            th = theta[bad]
            opt_r = _alternative_starts(self._axis_r, th[:, 1], sr[bad])
            opt_c = (_alternative_starts(self._axis_c, th[:, 2], sc[bad]) if self.d == 3
                     else [None])
            sub = g[bad]
            for a in opt_r:
                for b in opt_c:
                    if a is None and b is None:
                        continue
                    ra = sr[bad] if a is None else a
                    cb = None if self.d == 2 else (sc[bad] if b is None else b)
                    hole = np.isnan(sub)
                    if not hole.any():
                        break
                    alt = self._combine(th, ra, cb, loads=loads)
                    sub = np.where(hole, alt, sub)
            g[bad] = sub
        return g

    def __call__(self, theta, out=None) -> np.ndarray:
        """The deflections of candidates at the measured pressures.

        Parameters
        ----------
        theta : array_like, shape (N, d) or (d,)
            Candidates ``(log10 X1d, log10 r[, u])``.
        out : ndarray, shape (N, u), optional
            Receives the result.

        Returns
        -------
        ndarray, shape (N, u)
            Deflections (mm); NaN outside the space or beyond the reach of a ray.
        """
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        if theta.shape[1] != self.d:
            raise ValueError(f"candidates must have {self.d} columns, got {theta.shape}")
        n, u = theta.shape[0], self.pressure_mbar.size
        x1d = 10.0 ** theta[:, 0]
        # the scaling law: the candidate at p reads its ray at load p / X1d, i.e. at the
        # pressure p X1d_ref / X1d of the FE run; beyond the ray's reach: NaN
        q = reference_pressure(self.pressure_mbar[None, :], x1d[:, None], self.x1d_ref)  # (N, u)
        # the rays are combined up to the last load a stencil reads (a focused window
        # of stiff candidates reads a fraction of them)
        vals = self._load.evaluate(self.combined_logs(theta, loads=self._load.loads_for(q)), q)
        if out is None:
            return vals
        out[...] = vals
        return out


def read_at_once(calls) -> list:
    """The curves of several ray interpolants at candidates of the same X1d, at once.

    A fit with a given thickness reads its model's curve and the thickness's
    brackets (the rays at -1 and +1 sd) at the same X1d, so at the same loads
    p X1d_ref / X1d: their cells along the load are found once
    (:meth:`LoadAxis.stencils_of`), for each the same values as its own call.

    Parameters
    ----------
    calls : list of (interpolant, theta)
        Each theta (N, d) of its interpolant, all with the same first column
        (log10 X1d). An interpolant of other pressures or loads than the first
        (or not a :class:`RayInterpolant`) is read by its own call.

    Returns
    -------
    list of ndarray (N, u)
    """
    first, theta0 = calls[0]
    if not isinstance(first, RayInterpolant):
        return [f(theta) for f, theta in calls]
    theta0 = np.atleast_2d(np.asarray(theta0, dtype=float))
    q = reference_pressure(first.pressure_mbar[None, :], 10.0 ** theta0[:, 0][:, None],
                           first.x1d_ref)
    loads = first._load.loads_for(q)
    stencils, out = None, []
    for f, theta in calls:
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        if not (isinstance(f, RayInterpolant) and f.x1d_ref == first.x1d_ref
                and np.array_equal(f.pressure_mbar, first.pressure_mbar)
                and np.array_equal(f._load.loads, first._load.loads)
                and theta.shape[1] == f.d and np.array_equal(theta[:, 0], theta0[:, 0])):
            out.append(f(theta))
            continue
        g = f.combined_logs(theta, loads=loads)
        if stencils is None:
            stencils = first._load.stencils_of(q, g.shape)
        out.append(f._load.evaluate_at(g, stencils))
    return out
