"""Profile-likelihood confidence intervals on the interpolated simulated space.

Method
------
With Gaussian noise of sd sigma on every measured deflection,
``-2 ln L(theta) = chi2(theta) + const`` with ``chi2 = sum (residual / sigma)^2``.
The profile-likelihood interval of a scalar parameter ``g(theta)`` at level
``1 - a`` is ``{t : min over g(theta) = t of chi2(theta) - chi2_min <= q}``, with
``q`` the ``1 - a`` quantile of chi2(1), or of F(1, nu) when sigma was estimated
with nu degrees of freedom (the t-interval of a linear model).  That set is the
projection of the region ``{theta : chi2(theta) - chi2_min <= q}`` onto ``g``.
So one evaluation of chi2 on a dense grid around the optimum gives the interval
of every parameter at once, and of any function of them (X1h = X1d * X1h/X1d,
X2d = X1d * X2d/X1d): the interpolated space evaluates thousands of candidates
in one vectorised call.

Why this method
    The 6 mm cost valley is a curved banana in (X1d, X1h), X1h of a 2 mm curve
    is bounded by the edges of the space and not by the data (paper section
    3.2), and the scale-free axes are logarithms.  A linearised (Gauss-Newton)
    covariance gives a symmetric, unbounded ellipse: wrong on all three counts.
    MCMC (e.g. emcee) on the interpolated space gives Bayesian intervals that
    depend on a prior and need a burn-in and a convergence check per curve; a
    grid in 2 or 3 dimensions is exhaustive, deterministic and cheaper.

Grid
    Along the principal axes of the Gauss-Newton covariance at the optimum,
    ``+- 4`` standard errors each, clipped to the space: a thin diagonal valley
    lies along a grid axis instead of slipping between the points of a grid
    in theta (with an axis-aligned grid, 6 mm intervals covered 85 % instead of
    95 %).  Where the region touches a face of the grid that is not an edge of
    the space, the grid grows on that side; where it spans fewer than 8 cells
    along an axis, it shrinks around it.  The ends of an interval are refined by
    linear interpolation of chi2 between each grid point inside the region and
    its neighbours outside.

Model error
    When the residuals are larger than the noise explains (the reduced
    ``chi2_min / (n - d)`` above its 99th percentile under the noise), the
    threshold is multiplied by ``s = chi2_min / (n - d)`` (the Birge ratio;
    reported as ``misfit_scale``), so that a systematic misfit widens the
    interval instead of leaving a noise-only interval around a biased fit.

Open ends
    An interval that reaches an edge of the simulated space is reported with
    ``lower_open`` / ``upper_open``: within the space the data do not bound
    the parameter on that side (its true interval may extend further).

Examples
--------
A straight line ``y = a + b x`` with known noise: the profile-likelihood interval
is the classical ``estimate +- 1.96 se`` exactly.

>>> import numpy as np
>>> x = np.linspace(0, 1, 20); rng = np.random.default_rng(0)
>>> y = 1.0 + 2.0 * x + rng.normal(0, 0.1, x.size)
>>> def residuals(theta):  # (N, 2) -> (N, 20), in units of the noise sd
...     return (y - theta[:, :1] - theta[:, 1:] * x) / 0.1
>>> X = np.stack([np.ones_like(x), x], 1)
>>> fit = np.linalg.lstsq(X, y, rcond=None)[0]
>>> se = 0.1 * np.sqrt(np.diag(np.linalg.inv(X.T @ X)))
>>> ci = profile_intervals(residuals, fit, [-10, -10], [10, 10],
...                        {"a": lambda t: t[:, 0], "b": lambda t: t[:, 1]}, scale_misfit=False)
>>> b = ci.parameters["b"]
>>> bool(abs(b.lower - (fit[1] - 1.96 * se[1])) < 0.01 * se[1])
True
>>> bool(abs(b.upper - (fit[1] + 1.96 * se[1])) < 0.01 * se[1])
True
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import stats

__all__ = ["Interval", "LikelihoodIntervals", "profile_intervals", "interval_threshold"]

#: Grid points per axis, by the number of fitted parameters.
POINTS_PER_AXIS = {1: 401, 2: 81, 3: 25, 4: 13, 5: 9}
#: Half-width of the first box, in Gauss-Newton standard errors.
BOX_HALF_WIDTH_SE = 4.0
#: Fewest cells the region must span along each axis before the box is shrunk.
MIN_CELLS = 8
#: Curve values per vectorised call (candidates x points; 32 MB of float64): bounds
#: the memory of a call whatever the length of the curve.
CHUNK_VALUES = 4_000_000


@dataclass(frozen=True)
class Interval:
    """A confidence interval of one parameter."""

    estimate: float
    lower: float
    upper: float
    lower_open: bool = False  # the region reaches the space's edge on that side
    upper_open: bool = False

    def to_dict(self) -> dict:
        return {"estimate": self.estimate, "lower": self.lower, "upper": self.upper,
                "lower_open": self.lower_open, "upper_open": self.upper_open}

    def text(self, unit: str = "") -> str:
        """``[lo, hi]`` with ``<=`` / ``>=`` marks at open ends."""
        lo = ("<=" if self.lower_open else "") + f"{self.lower:.3g}"
        hi = (">=" if self.upper_open else "") + f"{self.upper:.3g}"
        return f"[{lo}, {hi}]" + (f" {unit}" if unit else "")


@dataclass
class LikelihoodIntervals:
    """Profile-likelihood intervals of several parameters of one fit."""

    parameters: dict
    correlation: dict
    level: float
    chi2_min: float
    threshold: float
    scale: float
    noise_dof: float
    n_points: int
    grid_points: int
    method: str = "profile likelihood on a grid of the interpolated simulated space"
    notes: list = field(default_factory=list)

    def to_dict(self) -> dict:
        return {"method": self.method, "level": self.level,
                **{k: v.to_dict() for k, v in self.parameters.items()},
                "correlation": self.correlation,
                "chi2_min": self.chi2_min, "delta_chi2_threshold": self.threshold,
                "misfit_scale": self.scale,
                "noise_dof": None if math.isinf(self.noise_dof) else self.noise_dof,
                "n_points": self.n_points, "grid_points": self.grid_points,
                "notes": list(self.notes)}


def interval_threshold(level: float, noise_dof: float = math.inf) -> float:
    """The chi2 rise that bounds a ``level`` interval of one parameter.

    The ``level`` quantile of chi2(1) for a known noise level, of F(1, nu) for a
    noise level estimated with ``nu`` degrees of freedom.

    >>> round(interval_threshold(0.95), 3), round(interval_threshold(0.95, 20), 3)
    (3.841, 4.351)
    """
    if math.isinf(noise_dof):
        return float(stats.chi2.ppf(level, 1))
    return float(stats.f.ppf(level, 1, noise_dof))


def _misfit_scale(chi2_min, dof, noise_dof, alpha=0.01) -> float:
    """The Birge ratio chi2_min / dof where it is significantly above 1, else 1.

    Scaling whenever chi2_min > dof would widen the intervals of a correct model
    half the time (measured: 97 % coverage instead of 95 % with an estimated
    noise level); only a misfit that the noise does not explain at level
    ``alpha`` (the reduced chi2 against F(dof, noise_dof)) widens them.
    """
    ratio = chi2_min / dof
    crit = (stats.chi2.ppf(1 - alpha, dof) / dof if math.isinf(noise_dof)
            else stats.f.ppf(1 - alpha, dof, noise_dof))
    return float(ratio) if ratio > crit else 1.0


def _chi2(residuals, theta, n_points):
    out = np.empty(theta.shape[0])
    chunk = max(16, CHUNK_VALUES // max(n_points, 1))
    for i in range(0, theta.shape[0], chunk):
        r = np.asarray(residuals(theta[i:i + chunk]), dtype=float)
        c = np.einsum("nt,nt->n", r, r)
        c[~np.isfinite(c)] = np.inf
        out[i:i + chunk] = c
    return out


def _gauss_newton(residuals, theta, lower, upper):
    """Covariance of theta (unit noise) from a central-difference Jacobian; None if singular."""
    d = theta.size
    h = 1e-4 * np.maximum(upper - lower, 1e-12)
    pts = []
    for a in range(d):
        lo, hi = theta.copy(), theta.copy()
        lo[a] = max(lower[a], theta[a] - h[a])
        hi[a] = min(upper[a], theta[a] + h[a])
        pts += [lo, hi]
    r = np.asarray(residuals(np.array(pts)), dtype=float)
    steps = np.array([pts[2 * a + 1][a] - pts[2 * a][a] for a in range(d)])
    J = (r[1::2] - r[0::2]).T / steps  # (n, d)
    if not np.all(np.isfinite(J)):
        return None
    try:
        cov = np.linalg.inv(J.T @ J)
    except np.linalg.LinAlgError:
        return None
    return cov if np.all(np.isfinite(cov)) and np.all(np.diag(cov) > 0) else None


def _straight_level_sets(parameters, theta, lower, upper, G) -> bool:
    """Whether every parameter's gradient keeps its direction across the space.

    Then its level sets are straight lines c . theta = const (X1d and X1h on
    either space) and its profile can be scanned along c.
    """
    probes = [np.clip(theta + f * (upper - lower), lower, upper)
              for f in ((0.17, -0.23), (-0.31, 0.29))]
    for p in probes:
        Gp = _gradients(parameters, p, lower, upper)
        for g0, g1 in zip(G, Gp):
            n0, n1 = np.linalg.norm(g0), np.linalg.norm(g1)
            if n0 == 0 or n1 == 0 or abs(g0 @ g1) / (n0 * n1) < 1 - 1e-6:
                return False
    return True


def _principal_axes(cov, span):
    """Principal directions of the covariance (columns) and their standard errors.

    Each error is capped so that the first grid (+- 4 of them) spans at most the
    space along that direction: a direction the data do not bound (X1h of a 2 mm
    curve) is then sampled across the space, not beyond it.
    """
    d = span.size
    if cov is None:
        return np.eye(d), span / (2 * BOX_HALF_WIDTH_SE)
    lam, vec = np.linalg.eigh(cov)
    lam = np.maximum(lam, 0.0)
    reach = np.abs(vec).T @ span  # extent of the space along each direction (upper bound)
    scales = np.minimum(np.sqrt(lam), reach / (2 * BOX_HALF_WIDTH_SE))
    return vec, np.maximum(scales, 1e-12 * reach)


def _rotated_grid(theta, axes, scales, z_lo, z_hi, m, lower, upper):
    """Grid points (z, theta clipped to the space, whether clipping moved them)."""
    lines = [np.linspace(lo, hi, m) for lo, hi in zip(z_lo, z_hi)]
    z = np.stack([g.reshape(-1) for g in np.meshgrid(*lines, indexing="ij")], axis=1)
    raw = theta + (z * scales) @ axes.T
    pts = np.clip(raw, lower, upper)
    return z, pts, np.any(pts != raw, axis=1)


def _crossings(pts, chi2, inside, shape, limit):
    """Points where chi2 crosses ``limit`` between inside grid points and outside neighbours."""
    d = len(shape)
    P = pts.reshape(*shape, d)
    C = chi2.reshape(shape)
    I = inside.reshape(shape)
    out = []
    for a in range(d):
        for step in (1, -1):
            i_sl = [slice(None)] * d
            j_sl = [slice(None)] * d
            i_sl[a] = slice(0, -1) if step == 1 else slice(1, None)
            j_sl[a] = slice(1, None) if step == 1 else slice(0, -1)
            i_sl, j_sl = tuple(i_sl), tuple(j_sl)
            pair = I[i_sl] & ~I[j_sl]
            if not pair.any():
                continue
            ci, cj = C[i_sl][pair], C[j_sl][pair]
            pi, pj = P[i_sl][pair], P[j_sl][pair]
            f = np.where(np.isfinite(cj), (limit - ci) / np.where(cj > ci, cj - ci, 1.0), 0.5)
            f = np.clip(f, 0.0, 1.0)[:, None]
            out.append(pi + f * (pj - pi))
    return np.concatenate(out) if out else np.empty((0, d))


#: Two-parameter profiles: values of the profiled coordinate across the space, points
#: of the first scan of the nuisance coordinate, zoom rounds and points per round.
PROFILE_U, PROFILE_W, ZOOM_ROUNDS, ZOOM_POINTS = 81, 61, 4, 9
#: Bisection steps that place an end of an interval between two profile values.
BISECTIONS = 12


def _line_range(point, direction, lower, upper):
    """Range of t where point + t * direction stays in the box (empty: lo > hi)."""
    lo, hi = -np.inf, np.inf
    for a in range(point.size):
        if abs(direction[a]) < 1e-15:
            if not lower[a] - 1e-12 <= point[a] <= upper[a] + 1e-12:
                return 1.0, -1.0
            continue
        t1 = (lower[a] - point[a]) / direction[a]
        t2 = (upper[a] - point[a]) / direction[a]
        lo, hi = max(lo, min(t1, t2)), min(hi, max(t1, t2))
    return lo, hi


class _Profile2D:
    """min over w of chi2(u c + w c_perp): the profile of the coordinate u = c . theta
    (evaluated, with other profiles, by :func:`_profiles`)."""

    def __init__(self, residuals, n, c, lower, upper):
        self.residuals, self.n = residuals, n
        self.c = c / np.linalg.norm(c)
        self.w_dir = np.array([-self.c[1], self.c[0]])
        self.lower, self.upper = lower, upper
        corners = np.array([[lower[0], lower[1]], [lower[0], upper[1]],
                            [upper[0], lower[1]], [upper[0], upper[1]]])
        self.u_range = (float((corners @ self.c).min()), float((corners @ self.c).max()))
        self.evaluations = 0


def _profiles(items):
    """[(profile chi2, argmin theta)] of several ``(_Profile2D, us)`` in one pass.

    Every u is minimised over w on its own (a scan of PROFILE_W points, then
    ZOOM_ROUNDS zooms), so the profiles of several parameters share each call
    of the residuals: half the calls for two parameters, the same numbers.
    """
    rows_c, rows_w, lo_all, hi_all, u_all, owner = [], [], [], [], [], []
    results = []
    for k, (prof, us) in enumerate(items):
        us = np.atleast_1d(np.asarray(us, dtype=float))
        out, best = np.full(us.size, np.inf), np.full((us.size, 2), np.nan)
        results.append((out, best))
        lo_w, hi_w = np.empty(us.size), np.empty(us.size)
        for j, u in enumerate(us):
            lo_w[j], hi_w[j] = _line_range(u * prof.c, prof.w_dir, prof.lower, prof.upper)
        ok = np.flatnonzero(hi_w >= lo_w)
        for j in ok:
            rows_c.append(prof.c)
            rows_w.append(prof.w_dir)
            lo_all.append(lo_w[j])
            hi_all.append(hi_w[j])
            u_all.append(us[j])
            owner.append((k, j))
    if not owner:
        return results
    c, wd = np.array(rows_c), np.array(rows_w)
    lo, hi, u = np.array(lo_all), np.array(hi_all), np.array(u_all)
    lower = np.array([items[k][0].lower for k, _ in owner])
    upper = np.array([items[k][0].upper for k, _ in owner])
    prof0 = items[0][0]
    frac = np.linspace(0.0, 1.0, PROFILE_W)
    w = lo[:, None] + (hi - lo)[:, None] * frac[None, :]
    cell = (hi - lo) / (PROFILE_W - 1)
    rows = np.arange(u.size)
    per_item = np.bincount([k for k, _ in owner], minlength=len(items))
    for rnd in range(ZOOM_ROUNDS + 1):
        theta = u[:, None, None] * c[:, None, :] + w[:, :, None] * wd[:, None, :]
        theta = np.clip(theta, lower[:, None, :], upper[:, None, :])
        chi2 = _chi2(prof0.residuals, theta.reshape(-1, 2), prof0.n).reshape(w.shape)
        for prof, rows_of in zip((p for p, _ in items), per_item):
            prof.evaluations += int(rows_of) * w.shape[1]
        j = np.argmin(chi2, axis=1)
        w_best, c_best = w[rows, j], chi2[rows, j]
        if rnd == ZOOM_ROUNDS:
            break
        # zoom around the best point: two cells either side first (a valley narrower
        # than a cell may sit beside the best point), then one
        reach = 2.0 if rnd == 0 else 1.0
        step = np.linspace(-reach, reach, ZOOM_POINTS)
        w = np.clip(w_best[:, None] + cell[:, None] * step[None, :], lo[:, None], hi[:, None])
        cell = cell * 2.0 * reach / (ZOOM_POINTS - 1)
    best_theta = np.clip(u[:, None] * c + w_best[:, None] * wd, lower, upper)
    for r, (k, jj) in enumerate(owner):
        results[k][0][jj] = c_best[r]
        results[k][1][jj] = best_theta[r]
    return results


def _profile_2d_intervals(residuals, theta, lower, upper, parameters, G, n, chi2_hat, level,
                          noise_dof, scale_misfit, fit_is_minimum):
    """Intervals of a two-parameter fit by profiles across the whole space.

    Each parameter is a monotone function of a linear combination c . theta (its
    gradient gives c: X1d = 10^theta0, X1h = 10^(theta0 + theta1) on the
    scale-free space; the moduli themselves on a grid space).  Its profile is
    scanned across the whole space (the 6 mm valley runs over decades), then
    each end is placed by bisection between the last value inside and the first
    outside the region.
    """
    profiles, grids = {}, {}
    for k, name in enumerate(parameters):
        c = G[k] if np.abs(G[k]).max() > 0 else np.eye(2)[k]
        prof = _Profile2D(residuals, n, c, lower, upper)
        u_hat = float(theta @ prof.c)
        profiles[name] = prof
        grids[name] = np.union1d(np.linspace(*prof.u_range, PROFILE_U), [u_hat])
    # every parameter's scan in the same calls of the residuals
    scanned = _profiles([(profiles[name], grids[name]) for name in parameters])
    scans = {name: (grids[name], v, th) for name, (v, th) in zip(parameters, scanned)}
    finite = [v[np.isfinite(v)] for _, v, _ in scans.values()]
    chi2_min = min([chi2_hat] + [float(v.min()) for v in finite if v.size])
    if not math.isfinite(chi2_min):
        raise ValueError("no candidate of the space near the fit has a curve")
    notes = []
    if fit_is_minimum and chi2_hat > chi2_min + 1e-6 * max(1.0, chi2_min):
        notes.append(f"the profile found a lower chi2 ({chi2_min:.4g}) than the fit "
                     f"({chi2_hat:.4g}): the fit is not the minimum")
    dof = max(n - 2, 1)
    scale = _misfit_scale(chi2_min, dof, noise_dof) if scale_misfit else 1.0
    limit = chi2_min + interval_threshold(level, noise_dof) * scale
    # each end of each interval: bisection between the last scan value inside the
    # region (a) and the first outside (b); every end of every parameter moves in the
    # same vectorised profile call per step
    ends, brackets = {}, {}
    for name in parameters:
        prof = profiles[name]
        us, values, thetas = scans[name]
        inside = np.flatnonzero(values <= limit)
        u_hat = float(theta @ prof.c)
        if inside.size == 0:  # the region is narrower than the scan: start at the fit
            i_hat = int(np.argmin(np.abs(us - u_hat)))
            inside = np.array([i_hat])
        ends[name], brackets[name] = [None, None], {}
        for side, (i_end, step) in enumerate(((int(inside.min()), -1),
                                              (int(inside.max()), +1))):
            j = i_end + step
            if j < 0 or j >= us.size:  # inside up to the edge of the space
                ends[name][side] = (thetas[i_end], True)
            else:
                brackets[name][side] = [us[i_end], us[j], thetas[i_end]]
    open_names = [name for name in parameters if brackets[name]]
    for _ in range(BISECTIONS if open_names else 0):
        mids = {name: np.array([0.5 * (b[0] + b[1]) for b in brackets[name].values()])
                for name in open_names}
        found = _profiles([(profiles[name], mids[name]) for name in open_names])
        for name, (v, t) in zip(open_names, found):
            for s, mid, vs, ts in zip(list(brackets[name]), mids[name], v, t):
                if vs <= limit:
                    brackets[name][s][0], brackets[name][s][2] = mid, ts
                else:
                    brackets[name][s][1] = mid
    intervals, total = {}, 0
    for k, (name, g) in enumerate(parameters.items()):
        prof = profiles[name]
        for s, (_, _, theta_a) in brackets[name].items():
            ends[name][s] = (theta_a, False)
        total += prof.evaluations
        # an end is also open where its best fit sits on an edge of the space along an
        # axis the parameter depends on (X1h of a 2 mm curve stops at the ratio's end)
        axes_of = np.abs(G[k]) > 1e-9 * np.abs(G[k]).max()
        tol = 1e-6 * (upper - lower)
        pair = [(t, is_open or bool(np.any(((t <= lower + tol) | (t >= upper - tol))[axes_of])))
                for t, is_open in ends[name]]
        pts = np.array([pair[0][0], pair[1][0], theta])
        vals = np.asarray(g(pts), dtype=float)
        est = float(vals[2])
        lo_i, hi_i = (0, 1) if vals[0] <= vals[1] else (1, 0)
        lower_open, upper_open = pair[lo_i][1], pair[hi_i][1]
        intervals[name] = Interval(est, float(min(vals[lo_i], est)), float(max(vals[hi_i], est)),
                                   bool(lower_open), bool(upper_open))
    return intervals, chi2_min, limit, scale, total, notes


def profile_intervals(residuals, theta_hat, lower, upper, parameters: dict, *,
                      level: float = 0.95, noise_dof: float = math.inf,
                      scale_misfit: bool = True, fit_is_minimum: bool = True,
                      points_per_axis: int | None = None,
                      max_rounds: int = 10) -> LikelihoodIntervals:
    """Profile-likelihood intervals of ``parameters`` around the fit ``theta_hat``.

    Parameters
    ----------
    residuals : callable
        ``(N, d) -> (N, n)``: the residuals of N candidates divided by the noise
        sd of each point (so that chi2 is their sum of squares); NaN or inf
        where a candidate has no curve.
    theta_hat : array (d,)
        The fit.
    lower, upper : array (d,)
        Bounds of the simulated space in the coordinates of theta.
    parameters : dict name -> callable ``(N, d) -> (N,)``
        The reported parameters as functions of theta (e.g. moduli in MPa).
    level : float
        Confidence level of each interval (one parameter at a time).
    noise_dof : float
        Degrees of freedom of the noise estimate (inf: known).
    scale_misfit : bool
        Widen by the Birge ratio when chi2_min exceeds ``n - d``.
    fit_is_minimum : bool
        ``theta_hat`` minimises this chi2 (else, e.g. for a weighted or ratio
        objective, the interval is around the likelihood's own minimum and no
        note is made when the grid finds a lower chi2).

    Returns
    -------
    LikelihoodIntervals
    """
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    theta = np.clip(np.asarray(theta_hat, dtype=float).reshape(-1), lower, upper)
    d = theta.size
    m = int(points_per_axis or POINTS_PER_AXIS.get(d, 15))
    r0 = np.asarray(residuals(theta[None, :]), dtype=float)[0]
    n = r0.size
    chi2_hat = float(np.sum(r0 ** 2)) if np.all(np.isfinite(r0)) else math.inf
    span = upper - lower
    cov = _gauss_newton(residuals, theta, lower, upper)
    G = _gradients(parameters, theta, lower, upper)
    if d == 2 and points_per_axis is None and _straight_level_sets(parameters, theta, lower,
                                                                    upper, G):
        intervals, chi2_min, limit, scale, total, notes = _profile_2d_intervals(
            residuals, theta, lower, upper, parameters, G, n, chi2_hat, level, noise_dof,
            scale_misfit, fit_is_minimum)
        return LikelihoodIntervals(intervals, _correlation(cov, G, list(parameters)), level,
                                   chi2_min, limit - chi2_min, scale, noise_dof, n, total,
                                   method="profile likelihood, scanned across the simulated "
                                          "space", notes=notes)
    axes_theta, scales = _principal_axes(cov, span)
    # the grid lives in z, theta = theta_hat + (z * scales) @ axes.T, clipped to the space:
    # a thin diagonal valley (the 6 mm banana) lies along a z axis instead of slipping
    # between the points of a grid in theta
    z_lo = np.full(d, -BOX_HALF_WIDTH_SE)
    z_hi = np.full(d, BOX_HALF_WIDTH_SE)
    notes, shrinks, total = [], 0, 0
    for _ in range(max_rounds):
        zs, pts, clipped = _rotated_grid(theta, axes_theta, scales, z_lo, z_hi, m, lower,
                                         upper)
        chi2 = _chi2(residuals, pts, n)
        total += pts.shape[0]
        chi2_min = min(chi2_hat, float(chi2.min()))
        if not math.isfinite(chi2_min):
            raise ValueError("no candidate of the space near the fit has a curve")
        dof = max(n - d, 1)
        scale = _misfit_scale(chi2_min, dof, noise_dof) if scale_misfit else 1.0
        limit = chi2_min + interval_threshold(level, noise_dof) * scale
        inside = chi2 <= limit
        changed = False
        cells = (z_hi - z_lo) / (m - 1)
        for a in range(d):
            # grow a face the region touches, unless the space's edge stops it there
            for face, side in ((z_lo, -1), (z_hi, +1)):
                on = inside & (np.abs(zs[:, a] - face[a]) < 0.5 * cells[a]) & ~clipped
                if on.any():
                    face[a] += side * (z_hi[a] - z_lo[a])
                    changed = True
        if changed:
            continue
        if shrinks < 2 and inside.any():
            inner = zs[inside]
            ext_lo, ext_hi = inner.min(axis=0), inner.max(axis=0)
            narrow = (ext_hi - ext_lo) < MIN_CELLS * cells
            if narrow.any():
                pad = np.maximum(0.5 * (ext_hi - ext_lo), 2 * cells)
                z_lo = np.where(narrow, ext_lo - pad, z_lo)
                z_hi = np.where(narrow, ext_hi + pad, z_hi)
                shrinks += 1
                continue
        break
    else:
        notes.append(f"the grid did not settle in {max_rounds} rounds")
    if fit_is_minimum and chi2_hat > chi2_min + 1e-6 * max(1.0, chi2_min):
        notes.append(f"the grid found a lower chi2 ({chi2_min:.4g}) than the fit "
                     f"({chi2_hat:.4g}): the fit is not the minimum")
    shape = (m,) * d
    tiny = 1e-9 * span
    edge = pts[inside]
    cross = _crossings(pts, chi2, inside, shape, limit)
    region = np.concatenate([edge, cross, theta[None, :]]) if cross.size else \
        np.concatenate([edge, theta[None, :]])
    # an end is open where the region meets an edge of the space along an axis the
    # parameter depends on (X1d of a 2 mm curve is bounded even where the region
    # meets the ends of the X1h axis)
    at_edge = (region <= lower + tiny) | (region >= upper - tiny)
    intervals = {}
    for k, (name, g) in enumerate(parameters.items()):
        values = np.asarray(g(region), dtype=float)
        est = float(np.asarray(g(theta[None, :]), dtype=float)[0])
        axes_of = np.abs(G[k]) > 1e-9 * np.abs(G[k]).max() if np.abs(G[k]).max() > 0 \
            else np.ones(d, bool)
        open_pt = at_edge[:, axes_of].any(axis=1)
        i_lo, i_hi = int(np.nanargmin(values)), int(np.nanargmax(values))
        intervals[name] = Interval(est, float(values[i_lo]), float(values[i_hi]),
                                   bool(open_pt[i_lo]), bool(open_pt[i_hi]))
    return LikelihoodIntervals(intervals, _correlation(cov, G, list(parameters)),
                               level, chi2_min, limit - chi2_min, scale, noise_dof, n,
                               total, notes=notes)


def _gradients(parameters, theta, lower, upper) -> np.ndarray:
    """d(parameter)/d(theta) at theta, (n_parameters, d), by finite differences."""
    d = theta.size
    h = 1e-6 * np.maximum(upper - lower, 1e-12)
    G = np.zeros((len(parameters), d))
    for a in range(d):
        lo, hi = theta.copy(), theta.copy()
        lo[a] = max(lower[a], theta[a] - h[a])
        hi[a] = min(upper[a], theta[a] + h[a])
        pair = np.stack([lo, hi])
        for k, g in enumerate(parameters.values()):
            v = np.asarray(g(pair), dtype=float)
            G[k, a] = (v[1] - v[0]) / (hi[a] - lo[a])
    return np.where(np.isfinite(G), G, 0.0)


def _correlation(cov, G, names) -> dict:
    """Local (Gauss-Newton) correlation of every pair of parameters."""
    if cov is None or len(names) < 2:
        return {}
    c = G @ cov @ G.T
    sd = np.sqrt(np.diag(c))
    out = {}
    for i in range(len(names)):
        for j in range(i + 1, len(names)):
            r = c[i, j] / (sd[i] * sd[j]) if sd[i] > 0 and sd[j] > 0 else math.nan
            out[f"{names[i]},{names[j]}"] = float(r) if math.isfinite(r) else None
    return out
