"""Cost functions of the identification (paper eqs. 4, 7, 10, 11-12).

An objective is a small object that maps candidates ``(N, 2) = (X1d, X1h)`` to
costs ``(N,)`` in one vectorised call, and knows

* ``lower``, ``upper``: the bounds of its simulated space(s), i.e. the initial
  window of the window focusing;
* ``residuals(candidates) -> (N, r)``: the vector whose half squared norm is the
  cost (used by the least-squares baseline);
* ``error(cost) -> E``: the correlation error of eq. 7 for a given cost, in
  ``error_unit``.

Non-converged parts of a space give NaN curves (see ``_interpolate``); every
objective maps a NaN cost to ``+inf``.

The correlation error (eq. 7) is ``E = (1/u) sqrt(sum_t d_t^2)``.  Note the
paper's ``1/u`` outside the square root (not an RMS).  As E is a monotone
function of the cost, ``E = sqrt(2 J) / u``; the objectives compute E from J.
For the multi-objective costs the paper defines no E; we use

* weighted (eq. 10): ``E = sqrt(2 J) / (alpha u2 + (1 - alpha) u6)`` in µm,
  which is eq. 7 of the 2 mm curve at alpha = 1 and of the 6 mm curve at
  alpha = 0;
* ratio (eqs. 11-12): eq. 7 applied to ``Gamma - Theta``, dimensionless.

A fit in units of the noise (the diagnosis, the time curves) subclasses
:class:`Chi2Objective`: its cost is chi^2 / 2, its E the RMS of the whitened
residuals.  All of them are objectives of the fitting engine (:mod:`._engine`).
"""

from __future__ import annotations

import math

import numpy as np

from skinsuction.space import GriddedSpace

__all__ = [
    "cost",
    "correlation_error",
    "SingleObjective",
    "WeightedObjective",
    "RatioObjective",
    "single_objective",
    "weighted_objective",
    "ratio_objective",
    "Chi2Objective",
]

MM_TO_UM = 1000.0


def cost(residuals) -> np.ndarray:
    """Eq. 4: ``J = 1/2 D^T D`` along the last axis; NaN -> +inf.

    Parameters
    ----------
    residuals : array_like (..., u)
        D, the differences between simulated and measured deflections.

    Returns
    -------
    ndarray (...)

    Examples
    --------
    >>> cost([[3.0, 4.0], [np.nan, 0.0]]).tolist()
    [12.5, inf]
    """
    d = np.asarray(residuals, dtype=float)
    j = 0.5 * np.einsum("...t,...t->...", d, d)
    j[np.isnan(j)] = np.inf
    return j


def correlation_error(residuals) -> np.ndarray:
    """Eq. 7: ``E = (1/u) sqrt(sum_t d_t^2)`` along the last axis (units of ``d``).

    Parameters
    ----------
    residuals : array_like (..., u)

    Returns
    -------
    ndarray (...)

    Examples
    --------
    >>> float(correlation_error([3.0, 4.0]))  # sqrt(25) / 2
    2.5
    """
    d = np.asarray(residuals, dtype=float)
    return np.sqrt(np.einsum("...t,...t->...", d, d)) / d.shape[-1]


def _curve_arrays(curve):
    """(pressure_mbar, deflection_mm, probe_mm or None) from a curve-like object."""
    if isinstance(curve, tuple):
        p, m = curve
        probe = None
    else:
        p, m = curve.pressure_mbar, curve.deflection_mm
        probe = getattr(curve, "probe_mm", None)
    p = np.asarray(p, dtype=float).reshape(-1)
    m = np.asarray(m, dtype=float).reshape(-1)
    if p.shape != m.shape or p.size == 0:
        raise ValueError("a measured curve needs as many deflections as pressures (>= 1)")
    if not (np.all(np.isfinite(p)) and np.all(np.isfinite(m))):
        raise ValueError("a measured curve must be finite")
    return p, m, probe


def _bounds_of(*objectives):
    lower = np.max([o.lower for o in objectives], axis=0)
    upper = np.min([o.upper for o in objectives], axis=0)
    if np.any(lower > upper):
        raise ValueError("the simulated spaces have no (X1d, X1h) range in common")
    return lower, upper


class SingleObjective:
    """Single-probe cost, eq. 4: ``J(x) = 1/2 sum_t (M_t - Omega_s(x, p_t))^2``.

    Parameters
    ----------
    space : GriddedSpace or NeoHookeanSlice
        Simulated space of the probe used for the measurement: the paper grid
        (candidates (X1d, X1h) in MPa) or the scale-free space (candidates
        (log10 X1d, log10 X1h/X1d); ``to_moduli`` maps them to MPa).
    curve : MeasuredCurve or (pressure_mbar, deflection_mm)
        The measured curve M(p).  Its pressures must lie inside the simulated
        pressure range; they need not be grid pressures.
    nan_policy : {"shift", "strict"}
        Stencils near non-converged points (see :class:`SpaceInterpolant`).

    Examples
    --------
    >>> from skinsuction.identify import analytic_surrogate_space
    >>> from skinsuction.space import evaluate
    >>> s = analytic_surrogate_space(6.0)
    >>> p = s.pressure_mbar
    >>> m = evaluate(s, [[0.0055, 0.00041]])[0]
    >>> obj = SingleObjective(s, (p, m))
    >>> obj([[0.0055, 0.00041], [0.03, 0.001]]).round(6).tolist()
    [0.0, 1.277206]
    """

    error_unit = "µm"

    def __init__(self, space: GriddedSpace, curve, nan_policy: str = "shift"):
        p, m, probe = _curve_arrays(curve)
        if probe is not None and not np.isclose(float(probe), space.probe_mm):
            raise ValueError(
                f"the curve was measured with the {float(probe):g} mm probe but the "
                f"space is for the {space.probe_mm:g} mm probe"
            )
        self.space = space
        self.pressure_mbar = p
        self.measured_mm = m
        # any layout of the space: candidates are moduli on a grid, logs on the scale-free one
        self.interpolant = space.interpolant_at(p, nan_policy)
        self.lower, self.upper = self.interpolant.lower, self.interpolant.upper
        self.to_moduli, self.from_moduli = space.to_moduli, space.from_moduli
        self.n_points = p.size
        self._buffer = np.empty((0, p.size))

    def curves(self, candidates) -> np.ndarray:
        """Omega_s(x, p_t) at the measured pressures, (N, u), mm."""
        return self.interpolant(candidates)

    def residuals(self, candidates) -> np.ndarray:
        """D(x) = M - Omega_s(x), (N, u), mm."""
        return self.measured_mm - self.interpolant(candidates)

    def __call__(self, candidates) -> np.ndarray:
        d = self._curves_in_buffer(candidates)
        np.subtract(self.measured_mm, d, out=d)
        return cost(d)

    def _curves_in_buffer(self, candidates) -> np.ndarray:
        """Curves in a reused buffer (valid until the next call): no page faults
        from allocating a large array at every iteration."""
        n = np.shape(candidates)[0]
        if self._buffer.shape[0] < n:
            self._buffer = np.empty((n, self.n_points))
        return self.interpolant(candidates, out=self._buffer[:n])

    def error(self, j) -> np.ndarray:
        """Eq. 7 in µm from the cost ``j`` (mm^2)."""
        return MM_TO_UM * np.sqrt(2.0 * np.asarray(j, dtype=float)) / self.n_points


class WeightedObjective:
    """Weighted two-probe cost, eq. 10: ``J = alpha J_2mm + (1 - alpha) J_6mm``.

    Parameters
    ----------
    objective_2mm, objective_6mm : SingleObjective
    alpha : float in [0, 1]
        Weight of the 2 mm cost.

    Examples
    --------
    >>> from skinsuction.identify import analytic_surrogate_space
    >>> from skinsuction.space import evaluate
    >>> x = [[0.0055, 0.00041]]
    >>> s2, s6 = analytic_surrogate_space(2.0), analytic_surrogate_space(6.0)
    >>> o2 = SingleObjective(s2, (s2.pressure_mbar, evaluate(s2, x)[0]))
    >>> o6 = SingleObjective(s6, (s6.pressure_mbar, evaluate(s6, x)[0] + 0.01))
    >>> w = WeightedObjective(o2, o6, alpha=0.5)
    >>> bool(np.isclose(w(x)[0], 0.5 * o6(x)[0]))
    True
    """

    error_unit = "µm"

    def __init__(self, objective_2mm: SingleObjective, objective_6mm: SingleObjective,
                 alpha: float = 0.5):
        alpha = float(alpha)
        if not 0.0 <= alpha <= 1.0:
            raise ValueError(f"alpha must lie in [0, 1], got {alpha}")
        self.objective_2mm = objective_2mm
        self.objective_6mm = objective_6mm
        self.alpha = alpha
        self.lower, self.upper = _bounds_of(objective_2mm, objective_6mm)
        self.to_moduli, self.from_moduli = objective_6mm.to_moduli, objective_6mm.from_moduli
        self.n_points = alpha * objective_2mm.n_points + (1 - alpha) * objective_6mm.n_points

    def residuals(self, candidates) -> np.ndarray:
        """``[sqrt(alpha) D_2mm, sqrt(1 - alpha) D_6mm]``, (N, u2 + u6), mm."""
        return np.concatenate(
            [
                np.sqrt(self.alpha) * self.objective_2mm.residuals(candidates),
                np.sqrt(1.0 - self.alpha) * self.objective_6mm.residuals(candidates),
            ],
            axis=1,
        )

    def __call__(self, candidates) -> np.ndarray:
        a = self.alpha
        j = np.zeros(np.asarray(candidates).shape[0])
        if a > 0:
            j = j + a * self.objective_2mm(candidates)
        if a < 1:
            j = j + (1 - a) * self.objective_6mm(candidates)
        return j

    def error(self, j) -> np.ndarray:
        """Weighted-count eq. 7 in µm (see module docstring)."""
        return MM_TO_UM * np.sqrt(2.0 * np.asarray(j, dtype=float)) / self.n_points


class RatioObjective:
    """Ratio cost, eqs. 11-12 with eq. 4: ``J = 1/2 sum_t (Gamma_t - Theta_t(x))^2``.

    ``Theta = Omega_6mm / Omega_2mm`` (eq. 11) and ``Gamma = M_6mm / M_2mm``
    (eq. 12) at the pressures common to both measured curves.  The ratio is 0/0
    at p = 0, so p = 0 is excluded, and so is any pressure where the measured
    2 mm deflection is 0 (``excluded_pressures_mbar`` lists them).  A candidate
    whose interpolated 2 mm deflection is 0 gets an infinite or NaN ratio, hence
    cost +inf.  Residuals are dimensionless, so ``error_unit`` is ``"1"``.

    Parameters
    ----------
    space_2mm, curve_2mm, space_6mm, curve_6mm
        Simulated spaces and measured curves of the two probes.

    Examples
    --------
    >>> from skinsuction.identify import analytic_surrogate_space
    >>> from skinsuction.space import evaluate
    >>> x = [[0.0055, 0.00041]]
    >>> s2, s6 = analytic_surrogate_space(2.0), analytic_surrogate_space(6.0)
    >>> p = s2.pressure_mbar
    >>> r = RatioObjective(s2, (p, evaluate(s2, x)[0]), s6, (p, evaluate(s6, x)[0]))
    >>> r.excluded_pressures_mbar.tolist(), r.n_points
    ([0.0], 50)
    >>> float(r(x)[0]) < 1e-25
    True
    """

    error_unit = "1"

    def __init__(self, space_2mm: GriddedSpace, curve_2mm, space_6mm: GriddedSpace, curve_6mm,
                 nan_policy: str = "shift"):
        p2, m2, probe2 = _curve_arrays(curve_2mm)
        p6, m6, probe6 = _curve_arrays(curve_6mm)
        for probe, space in ((probe2, space_2mm), (probe6, space_6mm)):
            if probe is not None and not np.isclose(float(probe), space.probe_mm):
                raise ValueError(
                    f"a {float(probe):g} mm curve was paired with the "
                    f"{space.probe_mm:g} mm space"
                )
        # pressures present in both curves (to 1e-9 mbar)
        i2, i6 = np.nonzero(np.isclose(p2[:, None], p6[None, :], rtol=0, atol=1e-9))
        if i2.size == 0:
            raise ValueError("the 2 mm and 6 mm curves have no pressure in common")
        p, m2, m6 = p2[i2], m2[i2], m6[i6]
        keep = (p != 0) & (m2 != 0)
        self.excluded_pressures_mbar = p[~keep]
        if not keep.any():
            raise ValueError("no pressure left for the ratio (all have p = 0 or M_2mm = 0)")
        p, m2, m6 = p[keep], m2[keep], m6[keep]
        self.pressure_mbar = p
        self.gamma = m6 / m2
        self.objective_2mm = SingleObjective(space_2mm, (p, m2), nan_policy)
        self.objective_6mm = SingleObjective(space_6mm, (p, m6), nan_policy)
        self.lower, self.upper = _bounds_of(self.objective_2mm, self.objective_6mm)
        self.to_moduli = self.objective_6mm.to_moduli
        self.from_moduli = self.objective_6mm.from_moduli
        self.n_points = p.size

    def theta(self, candidates) -> np.ndarray:
        """Eq. 11: Theta = Omega_6mm / Omega_2mm at the kept pressures, (N, u)."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return self.objective_6mm.curves(candidates) / self.objective_2mm.curves(candidates)

    def residuals(self, candidates) -> np.ndarray:
        """Gamma - Theta(x), (N, u), dimensionless; non-finite -> NaN."""
        d = self.gamma - self.theta(candidates)
        return np.where(np.isfinite(d), d, np.nan)

    def __call__(self, candidates) -> np.ndarray:
        d = self.objective_6mm._curves_in_buffer(candidates)
        with np.errstate(divide="ignore", invalid="ignore"):
            np.divide(d, self.objective_2mm._curves_in_buffer(candidates), out=d)
        np.subtract(self.gamma, d, out=d)
        return cost(d)  # inf or NaN residuals -> +inf

    def error(self, j) -> np.ndarray:
        """Eq. 7 of the ratio residuals (dimensionless)."""
        return np.sqrt(2.0 * np.asarray(j, dtype=float)) / self.n_points


def single_objective(space: GriddedSpace, curve, nan_policy: str = "shift") -> SingleObjective:
    """Single-probe objective (eq. 4); see :class:`SingleObjective`.

    Parameters
    ----------
    space : GriddedSpace or NeoHookeanSlice
        The probe's simulated space.
    curve : MeasuredCurve or (pressure_mbar, deflection_mm)
        The measured curve.
    nan_policy : {"shift", "strict"}
        Stencils near non-converged points (see :class:`SingleObjective`).

    Returns
    -------
    SingleObjective
    """
    return SingleObjective(space, curve, nan_policy)


def weighted_objective(space_2mm: GriddedSpace, curve_2mm, space_6mm: GriddedSpace,
                       curve_6mm, alpha: float = 0.5,
                       nan_policy: str = "shift") -> WeightedObjective:
    """Weighted two-probe objective (eq. 10, ``alpha`` on 2 mm); see :class:`WeightedObjective`.

    Parameters
    ----------
    space_2mm, curve_2mm : GriddedSpace, curve
        The smaller probe's space and curve.
    space_6mm, curve_6mm : GriddedSpace, curve
        The larger probe's.
    alpha : float
        Weight of the smaller probe, in [0, 1].
    nan_policy : str
        As for :func:`single_objective`.

    Returns
    -------
    WeightedObjective
    """
    return WeightedObjective(
        SingleObjective(space_2mm, curve_2mm, nan_policy),
        SingleObjective(space_6mm, curve_6mm, nan_policy),
        alpha,
    )


def ratio_objective(space_2mm: GriddedSpace, curve_2mm, space_6mm: GriddedSpace,
                    curve_6mm, nan_policy: str = "shift") -> RatioObjective:
    """Ratio objective (eqs. 11-12); see :class:`RatioObjective`.

    Parameters
    ----------
    space_2mm, curve_2mm : GriddedSpace, curve
        The smaller probe's space and curve.
    space_6mm, curve_6mm : GriddedSpace, curve
        The larger probe's.
    nan_policy : str
        As for :func:`single_objective`.

    Returns
    -------
    RatioObjective
    """
    return RatioObjective(space_2mm, curve_2mm, space_6mm, curve_6mm, nan_policy)


class Chi2Objective:
    """chi^2 / 2 of residuals in units of their sd: the objective of a least-squares fit.

    A subclass gives :meth:`blocks`, the whitened residuals of the candidates in
    blocks (e.g. one per probe: chi^2 adds the blocks' sums of squares in their
    order), and may give :meth:`prior_residuals`, the terms of a Gaussian prior
    (added to chi^2, not counted in the ``n`` points).

    Parameters
    ----------
    lower, upper : array_like (k,)
        The box of the parameters (the simulated space's).
    n : int
        The points fitted (the ``n`` of E = sqrt(chi^2 / n)).
    chunk_values : int, optional
        Evaluate the cost ``max(8, chunk_values // n)`` candidates at a time (the
        memory of long curves); None: all in one call.
    """

    error_unit = "1"

    def __init__(self, lower, upper, n: int, chunk_values: int | None = None):
        self.lower, self.upper = lower, upper
        self.n = int(n)
        self.chunk_values = chunk_values

    def blocks(self, candidates: np.ndarray) -> list:
        """``[(N, n_i)]``: the residuals of the ``(N, k)`` candidates over their sd."""
        raise NotImplementedError

    def prior_residuals(self, candidates: np.ndarray) -> np.ndarray:
        """``(N, m)`` terms of a Gaussian prior (none by default)."""
        return np.zeros((candidates.shape[0], 0))

    def __call__(self, candidates) -> np.ndarray:
        """chi^2 / 2 of each candidate, ``(N,)``; +inf where a residual is not finite."""
        theta = np.atleast_2d(np.asarray(candidates, dtype=float))
        size = theta.shape[0]
        step = size if self.chunk_values is None else max(8, self.chunk_values // max(self.n, 1))
        out = np.empty(size)
        for i in range(0, size, max(step, 1)):
            t = theta[i:i + step]
            chi2 = 0.0
            for r in self.blocks(t):
                chi2 = chi2 + np.einsum("nt,nt->n", r, r)
            prior = self.prior_residuals(t)
            if prior.shape[1]:
                chi2 = chi2 + np.sum(prior ** 2, axis=1)
            out[i:i + step] = 0.5 * chi2
        out[~np.isfinite(out)] = np.inf
        return out

    def residuals(self, candidates) -> np.ndarray:
        """``(N, r)``: every block and the prior's terms; NaN or inf where there is no curve."""
        theta = np.atleast_2d(np.asarray(candidates, dtype=float))
        return np.concatenate(list(self.blocks(theta)) + [self.prior_residuals(theta)], axis=1)

    def error(self, cost) -> float:
        """The RMS of the whitened residuals, ``sqrt(2 cost / n)``."""
        return math.sqrt(2.0 * cost / self.n)
