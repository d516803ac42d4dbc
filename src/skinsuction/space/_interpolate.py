"""The grid layout of one probe (:class:`GriddedSpace`) and Omega_s off its nodes:
piecewise cubic Lagrange interpolation, vectorised.

The paper (section 2.3) computes non-simulated values "with Lagrange's cubic
interpolation" of the simulated space.  Here every axis uses the local cubic
Lagrange polynomial through the 4 grid nodes around the point: the two nodes of
the cell that holds the point and one more on each side (shifted inwards at the
ends of the axis).  In (X1d, X1h) this is the tensor product, a 4 x 4 stencil.
Properties that follow and that the tests check:

* the interpolant is exact at grid nodes;
* it reproduces any polynomial of degree <= 3 in each variable exactly;
* it is local, so a non-converged (NaN) node only spoils the values whose
  stencil contains it.

NaN policy (non-converged FE points).  A non-converged node value is never
used.  In p only nodes with a non-zero weight count, so a measured pressure that
coincides with a grid pressure takes the node value even next to a NaN node.  In
(X1d, X1h), ``nan_policy="shift"`` (default): a candidate whose centred 4 x 4
stencil holds a NaN node (at any of the pressures) uses the nearest NaN-free 4 x
4 stencil that still contains its cell (shifted by one or two nodes, so still
interpolation, exact for cubics); only cells that no NaN-free stencil contains
give NaN.  The interpolant stays exact at the nodes but may jump across a cell
edge where neighbouring cells use different stencils.  ``nan_policy="strict"``:
NaN as soon as the centred stencil holds a NaN node, so the usable region ends
about one cell before a non-converged node.  (With the paper's grid and a single
non-converged corner X1d = 0.001, X1h = 1e-5 MPa, "strict" makes every candidate
with X1d < 0.019 and X1h < 0.00041 MPa unusable -- the test point of the paper
sits on that edge.)  The objectives turn a NaN curve into cost = +inf, so the
window focusing never keeps such a candidate among the Nb best.  Points outside
the grid are NaN too (no extrapolation).

Speed.  The measured pressures are fixed during an identification, so the space
is first interpolated in p once (:func:`interpolate_pressure`); every iteration
then only evaluates the 2-D (X1d, X1h) interpolant.  :class:`SpaceInterpolant`
precomputes the 4 x 4 x u stencil values of every stencil position; a call
computes the 16 tensor-product weights of all N candidates at once, groups the
candidates by stencil position and does one small matrix product per group.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._lagrange import LagrangeAxis

__all__ = ["GriddedSpace", "SpaceInterpolant", "interpolate_pressure", "evaluate"]


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

        Parameters
        ----------
        space : SimulatedSpace
            Anything with a method ``grid(probe_mm, **selection) -> (x1d, x1h,
            pressure_mbar, deflection_mm)`` (e.g.
            :class:`skinsuction.space.SimulatedSpace`).
        probe_mm : float
            Aperture (probe) diameter in mm.
        **selection
            Passed on to ``space.grid`` (``bottom``, the other axes' values by
            parameter path, ...).

        Returns
        -------
        GriddedSpace
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
        """What sets :attr:`pressure_range`, for error messages.

        Returns
        -------
        str
        """
        return "the pressures of the simulated grid"

    def interpolant_at(self, pressure_mbar, nan_policy: str = "shift"):
        """Omega_s at fixed pressures: a callable ``(N, 2) candidates -> (N, u) mm``
        with ``lower`` and ``upper`` (:class:`skinsuction.space.SpaceInterpolant`).

        Parameters
        ----------
        pressure_mbar : array_like, shape (u,)
            Strictly increasing pressures inside the grid's (e.g. a measured curve's).
        nan_policy : {"shift", "strict"}
            How stencils with non-converged nodes are handled (module docstring).

        Returns
        -------
        SpaceInterpolant

        Examples
        --------
        >>> p = np.arange(0.0, 101.0, 50.0)
        >>> s = GriddedSpace([1.0, 2.0], [1.0, 2.0], p, np.broadcast_to(p, (2, 2, 3)), 6)
        >>> s.interpolant_at([25.0])([[1.5, 1.5]]).tolist()
        [[25.0]]
        """
        return SpaceInterpolant(interpolate_pressure(self, pressure_mbar), nan_policy)

    @staticmethod
    def to_moduli(candidates) -> np.ndarray:
        """(N, 2) X1d, X1h in MPa of candidates (the grid's candidates are the moduli).

        Also :meth:`from_moduli` (the same map: the identity).

        Parameters
        ----------
        candidates : array_like, shape (N, 2) or (2,)
            Candidates (X1d, X1h) in MPa.

        Returns
        -------
        ndarray, shape (N, 2)
        """
        return np.atleast_2d(np.asarray(candidates, dtype=float))

    from_moduli = to_moduli


def interpolate_pressure(space: GriddedSpace, pressure_mbar) -> GriddedSpace:
    """The simulated space at other pressures: cubic Lagrange along p, once.

    Parameters
    ----------
    space : GriddedSpace
    pressure_mbar : array_like, shape (u,)
        Strictly increasing pressures inside the simulated range, e.g. those of a
        measured curve.

    Returns
    -------
    GriddedSpace
        Same (X1d, X1h) grid, deflections at ``pressure_mbar``.  A value is NaN
        if a node of its stencil (with non-zero weight) is NaN.

    Raises
    ------
    ValueError
        If a pressure lies outside the simulated pressure range.

    Examples
    --------
    >>> import numpy as np
    >>> p = np.arange(0.0, 101.0, 2.0)
    >>> s = GriddedSpace([1.0, 2.0], [1.0, 2.0], p, np.broadcast_to(p**3, (2, 2, 51)), 6)
    >>> float(interpolate_pressure(s, [3.0]).deflection_mm[0, 0, 0])  # 3**3 exactly
    27.0
    """
    p = np.asarray(pressure_mbar, dtype=float).reshape(-1)
    lo, hi = space.pressure_mbar[0], space.pressure_mbar[-1]
    bad = ~((p >= lo) & (p <= hi))
    if bad.any():
        raise ValueError(
            f"pressure {p[bad][0]!r} mbar is outside the simulated range "
            f"{lo:g}..{hi:g} mbar of the {space.probe_mm:g} mm space"
        )
    axis = LagrangeAxis(space.pressure_mbar)
    start, w = axis.weights(p)
    idx = start[:, None] + axis._offsets  # (u, m)
    nodes = space.deflection_mm[..., idx]  # (n1, n2, u, m)
    terms = np.where(w == 0.0, 0.0, w * nodes)  # a zero weight ignores a NaN node
    values = terms.sum(axis=-1)
    return GriddedSpace(space.x1d, space.x1h, p, values, space.probe_mm)


#: Fewer candidates per stencil position than this on average: gather each
#: candidate's stencil (one small product per candidate, in blocks of
#: GATHER_BLOCK) rather than one product per position.  Measured on the default
#: scale-free space: 0.7 against 1.2 µs per candidate for a profile scan (1 061
#: positions for 5 002 candidates), 0.33 against 0.53 µs the other way for a
#: window-focusing window (20 positions for 1 000).
GATHER_BELOW = 8
GATHER_BLOCK = 64


class SpaceInterpolant:
    """Omega_s(X1d, X1h) at fixed pressures, for many candidates at once.

    Parameters
    ----------
    space : GriddedSpace
        The space, already at the pressures wanted (see
        :func:`interpolate_pressure`).
    nan_policy : {"shift", "strict"}
        How stencils with non-converged (NaN) nodes are handled (module docstring).

    Examples
    --------
    >>> import numpy as np
    >>> x1d, x1h, p = np.linspace(0, 1, 5), np.linspace(0, 2, 6), np.array([1.0, 2.0])
    >>> m = (x1d[:, None, None] ** 3 * x1h[None, :, None] ** 2) * p  # cubic x quadratic
    >>> om = SpaceInterpolant(GriddedSpace(x1d, x1h, p, m, 6))
    >>> x = np.array([[0.3, 1.1], [0.7, 0.05]])
    >>> exact = (x[:, :1] ** 3 * x[:, 1:] ** 2) * p
    >>> bool(np.allclose(om(x), exact, rtol=1e-12, atol=1e-15))
    True
    """

    #: NaN policies of the (X1d, X1h) stencils (see the module docstring).
    NAN_POLICIES = ("shift", "strict")

    def __init__(self, space: GriddedSpace, nan_policy: str = "shift"):
        if nan_policy not in self.NAN_POLICIES:
            raise ValueError(f"nan_policy must be one of {self.NAN_POLICIES}, got {nan_policy!r}")
        self.space = space
        self.nan_policy = nan_policy
        self.axis_d = LagrangeAxis(space.x1d)
        self.axis_h = LagrangeAxis(space.x1h)
        md, mh = self.axis_d.m, self.axis_h.m
        u = space.pressure_mbar.size
        win = np.lib.stride_tricks.sliding_window_view(
            space.deflection_mm, (md, mh), axis=(0, 1)
        )  # (nsd, nsh, u, md, mh)
        stencils = np.moveaxis(win, 2, -1)  # (nsd, nsh, md, mh, u)
        self._stencils = np.ascontiguousarray(
            stencils.reshape(self.axis_d.n_starts * self.axis_h.n_starts, md * mh, u)
        )
        self.n_points = u
        self._n_stencils = self._stencils.shape[0]
        self._work = np.empty((0, u))
        self._cell_starts = None  # (n1 + 1, n2 + 1, 2): stencil starts by searchsorted result
        if nan_policy == "shift":
            bad = np.isnan(self._stencils).any(axis=(1, 2))
            if bad.any():
                self._cell_starts = self._clean_starts(
                    bad.reshape(self.axis_d.n_starts, self.axis_h.n_starts))

    def _clean_starts(self, bad: np.ndarray) -> np.ndarray:
        """Stencil starts (sd, sh) per (rd, rh) = searchsorted(side="right") results.

        The centred starts where their stencil is NaN-free, else the NaN-free
        starts closest to them among those whose stencil contains the cell.
        """
        ad, ah = self.axis_d, self.axis_h
        nd, nh = ad.nodes.size, ah.nodes.size
        table = np.empty((nd + 1, nh + 1, 2), dtype=np.intp)
        for rd in range(nd + 1):
            cd = min(max(rd - 1, 0), nd - 2)  # the cell (the last node belongs to the last)
            sd0 = ad._start_of[rd]
            options_d = range(max(cd - ad.m + 2, 0), min(cd, ad.n_starts - 1) + 1)
            for rh in range(nh + 1):
                ch = min(max(rh - 1, 0), nh - 2)
                sh0 = ah._start_of[rh]
                best = (sd0, sh0)
                if bad[sd0, sh0]:
                    options = [(abs(sd - sd0) + abs(sh - sh0), abs(sh - sh0), sd, sh)
                               for sd in options_d
                               for sh in range(max(ch - ah.m + 2, 0),
                                               min(ch, ah.n_starts - 1) + 1)
                               if not bad[sd, sh]]
                    if options:
                        best = min(options)[2:]
                table[rd, rh] = best
        return table

    @property
    def lower(self) -> np.ndarray:
        """Lower bounds (X1d, X1h) of the candidates: the grid's."""
        return self.space.lower

    @property
    def upper(self) -> np.ndarray:
        """Upper bounds (X1d, X1h) of the candidates: the grid's."""
        return self.space.upper

    def __call__(self, candidates, out=None) -> np.ndarray:
        """Interpolated curves for candidates (X1d, X1h).

        Not thread-safe: one interpolant per thread.

        Parameters
        ----------
        candidates : array_like, shape (N, 2)
            Candidates (X1d, X1h) in MPa.
        out : ndarray, shape (N, u), optional
            Receives the result (saves allocating a large array per call).

        Returns
        -------
        ndarray, shape (N, u)
            Deflections (mm) at the space's pressures; NaN outside the grid or
            where no NaN-free stencil holds the candidate's cell.
        """
        x = np.asarray(candidates, dtype=float)
        if x.ndim != 2 or x.shape[1] != 2:
            raise ValueError(f"candidates must have shape (N, 2), got {x.shape}")
        n = x.shape[0]
        if out is None:
            out = np.empty((n, self.n_points))
        if n == 0:
            return out
        sd, sh, basis = self._basis(x)
        key = sd * self.axis_h.n_starts + sh
        if self._n_stencils < 2**15:
            key = key.astype(np.int16)  # radix sort below
        first = key[0]
        if np.all(key == first):  # one stencil position: one product
            np.matmul(basis, self._stencils[first], out=out)
            return out
        # group the candidates by stencil position, one product per group
        order = np.argsort(key, kind="stable")
        sorted_key = key[order]
        cuts = np.flatnonzero(sorted_key[1:] != sorted_key[:-1]) + 1
        if cuts.size + 1 > n // GATHER_BELOW:
            # spread candidates (a profile scans the whole space): few per stencil, so
            # gather each candidate's stencil instead, in cache-sized blocks
            for a in range(0, n, GATHER_BLOCK):
                b = min(n, a + GATHER_BLOCK)
                np.matmul(basis[a:b, None, :], self._stencils[key[a:b]], out=out[a:b, None, :])
            return out
        sorted_basis = basis[order]
        edges = np.concatenate(([0], cuts, [n]))
        scratch = self._scratch(n)
        for a, b in zip(edges[:-1].tolist(), edges[1:].tolist()):
            np.matmul(sorted_basis[a:b], self._stencils[sorted_key[a]], out=scratch[a:b])
        out[order] = scratch
        return out

    def _basis(self, x):
        """Stencil starts (N,), (N,) and tensor-product weights (N, md * mh).

        The starts are the centred ones, or with NaN policy "shift" those of
        ``_cell_starts`` (NaN-free stencils that hold the cell)."""
        ad, ah = self.axis_d, self.axis_h
        xd, xh = x[:, 0], x[:, 1]
        rd = np.searchsorted(ad.nodes, xd, side="right")
        rh = np.searchsorted(ah.nodes, xh, side="right")
        if self._cell_starts is not None:
            starts = self._cell_starts[rd, rh]
            sd, sh = starts[:, 0], starts[:, 1]
        else:
            sd, sh = ad._start_of[rd], ah._start_of[rh]
        wd, wh = ad.weights_at(xd, sd), ah.weights_at(xh, sh)
        # the tensor product, rows in the order of the stencil (d outer, h inner)
        basis = (wd[:, :, None] * wh[:, None, :]).reshape(x.shape[0], -1)
        outside = (rd == 0) | ~(xd <= ad.nodes[-1]) | (rh == 0) | ~(xh <= ah.nodes[-1])
        if outside.any():
            basis[outside] = np.nan
        return sd, sh, basis

    def _scratch(self, n: int) -> np.ndarray:
        if self._work.shape[0] < n:
            self._work = np.empty((n, self.n_points))
        return self._work[:n]


def evaluate(space: GriddedSpace, candidates, pressure_mbar=None) -> np.ndarray:
    """Omega_s for candidates at some pressures, once.

    Convenience for one-off use; an identification builds the
    :class:`SpaceInterpolant` once instead.

    Parameters
    ----------
    space : GriddedSpace
    candidates : array_like, shape (N, 2)
        Candidates (X1d, X1h) in MPa.
    pressure_mbar : array_like, shape (u,), optional
        Pressures (mbar); default: the space's.

    Returns
    -------
    ndarray, shape (N, u)
        Deflections (mm).

    Examples
    --------
    >>> from skinsuction.identify import analytic_surrogate_space
    >>> s = analytic_surrogate_space(6.0)
    >>> evaluate(s, [[0.0055, 0.00041]], [50.0, 100.0]).shape
    (1, 2)
    """
    if pressure_mbar is not None:
        space = interpolate_pressure(space, pressure_mbar)
    return SpaceInterpolant(space)(candidates)
