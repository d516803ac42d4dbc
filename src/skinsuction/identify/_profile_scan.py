"""Profile intervals of a two-parameter fit, scanned across the whole space.

Where each reported parameter is a monotone function of one linear combination
``c . theta`` (X1d = 10^theta0, X1h = 10^(theta0 + theta1) on the scale-free
space; the moduli themselves on a grid space), its profile ``min over w of
chi2(u c + w c_perp)`` is scanned over the whole range of ``u`` in the space (the
6 mm valley runs over decades), each ``u`` minimised over ``w`` by a scan and
zooms, and each end of the interval is placed by bisection.  Used by
:func:`._intervals.profile_intervals` for two parameters; other fits take the
rotated grid (:mod:`._profile_grid`).
"""

from __future__ import annotations

import math

import numpy as np

from ._likelihood import Interval, chi2_values, gradients, interval_threshold, misfit_scale

__all__ = ["straight_level_sets", "profile_2d_intervals"]


def straight_level_sets(parameters, theta, lower, upper, G) -> bool:
    """Whether every parameter's gradient keeps its direction across the space.

    Then its level sets are straight lines c . theta = const (X1d and X1h on
    either space) and its profile can be scanned along c.

    Parameters
    ----------
    parameters : dict
        name -> callable ``(N, 2) -> (N,)``.
    theta : ndarray (2,)
        The fit.
    lower, upper : ndarray (2,)
        The bounds.
    G : ndarray (n_parameters, 2)
        The gradients at the fit.

    Returns
    -------
    bool
    """
    probes = [np.clip(theta + f * (upper - lower), lower, upper)
              for f in ((0.17, -0.23), (-0.31, 0.29))]
    for p in probes:
        Gp = gradients(parameters, p, lower, upper)
        for g0, g1 in zip(G, Gp):
            n0, n1 = np.linalg.norm(g0), np.linalg.norm(g1)
            if n0 == 0 or n1 == 0 or abs(g0 @ g1) / (n0 * n1) < 1 - 1e-6:
                return False
    return True



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
        chi2 = chi2_values(prof0.residuals, theta.reshape(-1, 2), prof0.n).reshape(w.shape)
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


def _bisect_ends(profiles, scans, parameters, theta, limit):
    """Each end of each interval: ``(theta, open)`` where the scan is inside up to the
    edge of the space, else a bracket ``[u inside, u outside, theta inside]`` narrowed
    by bisection (every end of every parameter in the same profile call per step)."""
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
    return ends, brackets


def profile_2d_intervals(residuals, theta, lower, upper, parameters, G, n, chi2_hat, level,
                         noise_dof, scale_misfit, fit_is_minimum):
    """Intervals of a two-parameter fit by profiles across the whole space.

    Each parameter is a monotone function of a linear combination c . theta (its
    gradient gives c: X1d = 10^theta0, X1h = 10^(theta0 + theta1) on the
    scale-free space; the moduli themselves on a grid space).  Its profile is
    scanned across the whole space (the 6 mm valley runs over decades), then
    each end is placed by bisection between the last value inside and the first
    outside the region.

    Parameters
    ----------
    residuals : callable
        ``(N, 2) -> (N, n)`` residuals in units of the noise sd.
    theta : ndarray (2,)
        The fit, within the bounds.
    lower, upper : ndarray (2,)
        The bounds of the space.
    parameters : dict
        name -> callable ``(N, 2) -> (N,)``.
    G : ndarray (n_parameters, 2)
        Their gradients at the fit (:func:`straight_level_sets` holds).
    n : int
        Residuals per candidate.
    chi2_hat : float
        chi2 at the fit.
    level, noise_dof, scale_misfit, fit_is_minimum
        As for :func:`._intervals.profile_intervals`.

    Returns
    -------
    intervals, chi2_min, limit, scale, evaluations, notes
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
    scale = misfit_scale(chi2_min, dof, noise_dof) if scale_misfit else 1.0
    limit = chi2_min + interval_threshold(level, noise_dof) * scale
    ends, brackets = _bisect_ends(profiles, scans, parameters, theta, limit)
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

