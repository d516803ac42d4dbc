"""The simulated space Omega_s of one probe, as plain arrays on a regular grid."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["GriddedSpace"]


def _axis(name: str, values, min_size: int = 2) -> np.ndarray:
    a = np.array(values, dtype=float).reshape(-1)
    if a.size < min_size:
        raise ValueError(f"{name}: a grid axis needs at least {min_size} nodes, got {a.size}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: grid nodes must be finite")
    if not np.all(np.diff(a) > 0):
        raise ValueError(f"{name}: grid nodes must be strictly increasing")
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class GriddedSpace:
    """Simulated space Omega_s(X1d, X1h, p) of one probe on a regular grid (paper eq. 2-3).

    Parameters
    ----------
    x1d : array_like, shape (n1,)
        Dermis moduli X1^d (MPa), strictly increasing.
    x1h : array_like, shape (n2,)
        Hypodermis moduli X1^h (MPa), strictly increasing.
    pressure_mbar : array_like, shape (n_p,)
        Suction pressures (mbar), strictly increasing (one pressure is allowed).
    deflection_mm : array_like, shape (n1, n2, n_p)
        Apex deflection M (mm); NaN where the FE model did not converge.
    probe_mm : float
        Aperture (probe) diameter (mm).

    The arrays are copied and made read-only, so a space cannot change under an
    identification that uses it.

    Examples
    --------
    >>> import numpy as np
    >>> s = GriddedSpace([0.01, 0.02], [1e-4, 2e-4], [0.0, 50.0],
    ...                  np.zeros((2, 2, 2)), probe_mm=6)
    >>> s.shape
    (2, 2, 2)
    >>> s.lower, s.upper
    (array([0.01  , 0.0001]), array([0.02  , 0.0002]))
    """

    x1d: np.ndarray
    x1h: np.ndarray
    pressure_mbar: np.ndarray
    deflection_mm: np.ndarray
    probe_mm: float

    def __post_init__(self):
        set_ = object.__setattr__
        set_(self, "x1d", _axis("x1d", self.x1d))
        set_(self, "x1h", _axis("x1h", self.x1h))
        set_(self, "pressure_mbar", _axis("pressure_mbar", self.pressure_mbar, 1))
        m = np.array(self.deflection_mm, dtype=float)
        expected = (self.x1d.size, self.x1h.size, self.pressure_mbar.size)
        if m.shape != expected:
            raise ValueError(
                f"deflection_mm has shape {m.shape}, expected (n1, n2, n_p) = {expected}"
            )
        m.setflags(write=False)
        set_(self, "deflection_mm", m)
        probe = float(self.probe_mm)
        if not (np.isfinite(probe) and probe > 0):
            raise ValueError(f"probe_mm must be a positive number, got {self.probe_mm!r}")
        set_(self, "probe_mm", probe)

    @classmethod
    def from_space(cls, space, probe_mm: float, **selection) -> "GriddedSpace":
        """Take the grid of one probe from a stored simulated space.

        ``space`` is anything with a method
        ``grid(probe_mm, **selection) -> (x1d, x1h, pressure_mbar, deflection_mm)``
        (e.g. :class:`skinsuction.space.SimulatedSpace`); ``selection`` is passed on
        (``bottom``, ``x2d``, ...).
        """
        x1d, x1h, p, m = space.grid(probe_mm, **selection)
        return cls(x1d, x1h, p, m, probe_mm)

    @property
    def shape(self) -> tuple[int, int, int]:
        """(n1, n2, n_p)."""
        return self.deflection_mm.shape

    @property
    def lower(self) -> np.ndarray:
        """Lower bounds (X1d, X1h) of the space: the initial window."""
        return np.array([self.x1d[0], self.x1h[0]])

    @property
    def upper(self) -> np.ndarray:
        """Upper bounds (X1d, X1h) of the space: the initial window."""
        return np.array([self.x1d[-1], self.x1h[-1]])

    @property
    def converged(self) -> np.ndarray:
        """Boolean (n1, n2, n_p): True where the FE model gave a deflection."""
        return np.isfinite(self.deflection_mm)

    # -- the layout-independent face of a space (:class:`skinsuction.space.ProbeSpace`)
    layout = "grid"
    coordinates = ("X1d", "X1h")

    @property
    def pressure_range(self) -> tuple[float, float]:
        """Pressures (mbar) a measured curve may span: those of the grid."""
        return float(self.pressure_mbar[0]), float(self.pressure_mbar[-1])

    def range_note(self) -> str:
        """What sets :attr:`pressure_range`, for error messages."""
        return "the pressures of the simulated grid"

    def interpolant_at(self, pressure_mbar, nan_policy: str = "shift"):
        """Omega_s at fixed pressures: a callable ``(N, 2) candidates -> (N, u) mm``
        with ``lower`` and ``upper`` (:class:`skinsuction.space.SpaceInterpolant`).

        Examples
        --------
        >>> p = np.arange(0.0, 101.0, 50.0)
        >>> s = GriddedSpace([1.0, 2.0], [1.0, 2.0], p, np.broadcast_to(p, (2, 2, 3)), 6)
        >>> s.interpolant_at([25.0])([[1.5, 1.5]]).tolist()
        [[25.0]]
        """
        from ._interpolate import SpaceInterpolant, interpolate_pressure

        return SpaceInterpolant(interpolate_pressure(self, pressure_mbar), nan_policy)

    @staticmethod
    def to_moduli(candidates) -> np.ndarray:
        """(N, 2) X1d, X1h in MPa of candidates (the grid's candidates are the moduli)."""
        return np.atleast_2d(np.asarray(candidates, dtype=float))

    from_moduli = to_moduli
