"""The neo-Hookean scale-free space of one probe, as the identification reads it.

:class:`NeoHookeanSlice` is the neo-Hookean space of one probe in the shape the
identification asks of every layout (:class:`skinsuction.space.ProbeSpace`),
tabulated once per pressure protocol (:class:`TabulatedInterpolant`) off its rays
(:class:`skinsuction.space.RayInterpolant`).
"""

from __future__ import annotations

import copy
import math

import numpy as np

from ._interpolate import GriddedSpace, SpaceInterpolant
from ._ray_interpolate import RayInterpolant
from ._ray_space import RaySpace

__all__ = ["NeoHookeanSlice", "TabulatedInterpolant"]

#: Table nodes kept beyond a window: a cubic stencil of a cell inside, shifted off NaN
#: nodes, reaches three.
_WINDOW_MARGIN = 4


class NeoHookeanSlice:
    """The neo-Hookean scale-free space of one probe, for the identification objectives.

    What :class:`skinsuction.identify.SingleObjective` needs of a space: a
    probe, an interpolant at the measured pressures and the map of its
    candidates to moduli.  The candidates are ``theta = (log10 X1d, log10 X1h/X1d)``,
    so the window focusing samples decades evenly and the window is the box of
    the space (the X1d window of the configuration, its lower end raised to
    ``p_max / load_max``).

    Parameters
    ----------
    space : RaySpace
        The neo-Hookean space (or a cause's space, whose neutral rays are used).
    probe_mm : float
    """

    layout = "scale_free"
    coordinates = ("log10 X1d", "log10 X1h/X1d")

    def __init__(self, space: RaySpace, probe_mm: float):
        self.space = space.null_slice()
        self.space.rays(probe_mm)  # KeyError naming the probes if absent
        self.probe_mm = float(probe_mm)

    @property
    def pressure_range(self) -> tuple[float, float]:
        """Pressures (mbar) a measured curve may span: up to the space's reach."""
        return 0.0, float(self.space.spec.reach_mbar())

    def range_note(self) -> str:
        """What sets :attr:`pressure_range`, for error messages.

        Returns
        -------
        str
        """
        sp = self.space.spec
        return (f"the reach of the scale-free space: p/X1d <= {sp.load_max:g} mbar/MPa "
                f"up to X1d = {sp.x1d_range[1]:g} MPa")

    def interpolant_at(self, pressure_mbar, nan_policy: str = "shift") -> "TabulatedInterpolant":
        """The space at fixed pressures (candidates theta), tabulated once per protocol.

        Parameters
        ----------
        pressure_mbar : array_like, shape (u,)
            The measured pressures (mbar).
        nan_policy : {"shift"}
            Only the NaN policy "shift" is implemented for the scale-free layout.

        Returns
        -------
        TabulatedInterpolant
            Shared by every call with the same pressures (the last 16 protocols).
        """
        if nan_policy != "shift":
            raise ValueError(f"nan_policy {nan_policy!r}: the scale-free space uses 'shift'")
        # a study measures every subject with the same protocol: tabulate it once
        p = np.asarray(pressure_mbar, dtype=float)
        key = p.tobytes()
        cache = self.__dict__.setdefault("_tables", {})
        if key not in cache:
            if len(cache) >= 16:
                cache.pop(next(iter(cache)))
            cache[key] = TabulatedInterpolant(self.space, self.probe_mm, p,
                                              window=self.__dict__.get("_window"))
        return cache[key]

    def windowed(self, lower: float, upper: float) -> "NeoHookeanSlice":
        """This slice with its tables only over ``lower <= log10 X1d <= upper``.

        A polish near an estimate reads a fraction of the X1d window: its tables cost
        that fraction.  Candidates outside read NaN and are counted
        (:meth:`read_outside`), so that a caller can redo the fit on the whole table;
        inside, every value is the whole table's.

        Parameters
        ----------
        lower, upper : float
            The window of log10 X1d (clipped to the space's).

        Returns
        -------
        NeoHookeanSlice
        """
        out = copy.copy(self)
        out.__dict__.pop("_tables", None)
        out._window = (float(lower), float(upper))
        return out

    def read_outside(self) -> int:
        """Candidates read outside the window of :meth:`windowed` so far (0 without)."""
        return sum(t.outside for t in self.__dict__.get("_tables", {}).values())

    @staticmethod
    def to_moduli(theta) -> np.ndarray:
        """X1d, X1h in MPa of candidates theta.

        Parameters
        ----------
        theta : array_like, shape (N, 2) or (2,)
            Candidates ``(log10 X1d, log10 X1h/X1d)``.

        Returns
        -------
        ndarray, shape (N, 2)
        """
        t = np.atleast_2d(np.asarray(theta, dtype=float))
        x1d = 10.0 ** t[:, 0]
        return np.stack([x1d, x1d * 10.0 ** t[:, 1]], axis=1)

    @staticmethod
    def from_moduli(x) -> np.ndarray:
        """Candidates theta of moduli (inverse of :meth:`to_moduli`).

        Parameters
        ----------
        x : array_like, shape (N, 2) or (2,)
            X1d, X1h in MPa.

        Returns
        -------
        ndarray, shape (N, 2)
            ``(log10 X1d, log10 X1h/X1d)``.
        """
        x = np.atleast_2d(np.asarray(x, dtype=float))
        return np.stack([np.log10(x[:, 0]), np.log10(x[:, 1] / x[:, 0])], axis=1)


class TabulatedInterpolant:
    """The neo-Hookean space of one probe at fixed pressures, tabulated for speed.

    The rays are read once (:class:`RayInterpolant`) on a fine grid of
    ``log10 X1d`` (``step`` decades, over the X1d window) times the ratio nodes,
    at the measured pressures; candidates are then interpolated by the 4 x 4
    cubic stencils of the identification (:class:`skinsuction.identify.SpaceInterpolant`,
    NaN policy "shift") on ``log M``, exactly as the paper grid is, so one
    iteration of the window focusing costs what it costs on the paper grid.
    Along log X1d the table is much finer than M varies (0.01 decades: M moves
    by about 2 % between nodes), so it adds an error far below the rays' own.

    Parameters
    ----------
    space : RaySpace
        The neo-Hookean space.
    probe_mm : float
    pressure_mbar : array_like (u,)
        The measured pressures (mbar).
    step : float
        Spacing of the table in log10 X1d (decades).
    window : (float, float), optional
        Tabulate only these log10 X1d (and the nodes their stencils reach): a
        candidate outside reads NaN and counts in :attr:`outside`.

    Attributes
    ----------
    lower, upper : ndarray (2,)
        Bounds of theta = (log10 X1d, log10 X1h/X1d), as :class:`RayInterpolant`'s.
    """

    def __init__(self, space: RaySpace, probe_mm: float, pressure_mbar, step: float = 0.01,
                 window=None):
        rays = RayInterpolant(space, probe_mm, pressure_mbar)
        if rays.d != 2:
            raise ValueError("only the neo-Hookean space is tabulated")
        self.lower, self.upper = rays.lower, rays.upper
        self.pressure_mbar = rays.pressure_mbar
        n = max(4, int(math.ceil((self.upper[0] - self.lower[0]) / step)) + 1)
        lx = np.linspace(self.lower[0], self.upper[0], n)
        self.window, self.outside = (-np.inf, np.inf), 0
        if window is not None:
            # the same nodes as the whole table's, and as many beyond the window as a
            # (shifted) stencil of a cell inside reaches: the same values inside
            i = max(int(np.searchsorted(lx, window[0], "right")) - 1, 0)  # the cells of
            j = min(int(np.searchsorted(lx, window[1])) + 1, n)  # the window, whole
            a, b = max(i - _WINDOW_MARGIN, 0), min(j + _WINDOW_MARGIN, n)
            self.window = (lx[a + _WINDOW_MARGIN] if a > 0 else -np.inf,
                           lx[b - 1 - _WINDOW_MARGIN] if b < n else np.inf)
            lx = lx[a:b]
            n = lx.size
        lr = np.log10(np.asarray(space.spec.ratio_nodes))
        grid = np.stack(np.meshgrid(lx, lr, indexing="ij"), axis=-1).reshape(-1, 2)
        self._pos = self.pressure_mbar > 0
        # in chunks: a 2000-point curve on the whole table is 1e7 values per stencil node
        chunk = max(16, 2_000_000 // max(self.pressure_mbar.size, 1))
        m = np.concatenate([rays(grid[i:i + chunk]) for i in range(0, grid.shape[0], chunk)])
        with np.errstate(divide="ignore", invalid="ignore"):
            g = np.log(m[:, self._pos])
        g[~np.isfinite(g)] = np.nan
        table = GriddedSpace(lx, lr, self.pressure_mbar[self._pos],
                             g.reshape(n, lr.size, -1), probe_mm)
        self._log_m = SpaceInterpolant(table, "shift")
        # the usual protocol has p = 0 first (or not at all): a slice, not a mask
        first = int(np.argmax(self._pos)) if self._pos.any() else self._pos.size
        self._positive = slice(first, None) if self._pos[first:].all() else self._pos
        self._buffer = np.empty((0, int(self._pos.sum())))

    def __call__(self, candidates, out=None) -> np.ndarray:
        """The deflections of candidates at the tabulated pressures.

        Parameters
        ----------
        candidates : array_like, shape (N, 2) or (2,)
            Candidates ``(log10 X1d, log10 X1h/X1d)``.
        out : ndarray, shape (N, u), optional
            Receives the result.

        Returns
        -------
        ndarray, shape (N, u)
            Deflections (mm), 0 at p = 0.
        """
        cand = np.atleast_2d(np.asarray(candidates, dtype=float))
        n = cand.shape[0]
        if out is None:
            out = np.empty((n, self.pressure_mbar.size))
        out[:, ~self._pos] = 0.0
        if self._buffer.shape[0] < n:
            self._buffer = np.empty((n, self._buffer.shape[1]))
        log_m = self._log_m(cand, out=self._buffer[:n])
        away = ~((cand[:, 0] >= self.window[0]) & (cand[:, 0] <= self.window[1]))
        if away.any():
            log_m[away] = np.nan
            self.outside += int(away.sum())
        if isinstance(self._positive, slice):
            np.exp(log_m, out=out[:, self._positive])
        else:
            out[:, self._positive] = np.exp(log_m)
        return out
