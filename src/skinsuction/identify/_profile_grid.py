"""Profile intervals on a grid along the principal axes of the fit.

The grid lives in z, ``theta = theta_hat + (z * scales) @ axes.T`` (the principal
axes and standard errors of the Gauss-Newton covariance), clipped to the space:
a thin diagonal valley (the 6 mm banana) lies along a z axis instead of slipping
between the points of a grid in theta.  It starts at +- 4 standard errors, grows
on a face the region touches (unless that face is an edge of the space) and
shrinks around a region narrower than 8 cells; the region is then the grid
points inside and the crossings of the threshold between them and their
neighbours outside, and each interval is the range of its parameter over the
region.  Used by :func:`._intervals.profile_intervals` where the two-parameter
scan (:mod:`._profile_scan`) does not apply.
"""

from __future__ import annotations

import math

import numpy as np

from ._likelihood import Interval, chi2_values, interval_threshold, misfit_scale

__all__ = ["POINTS_PER_AXIS", "grid_intervals"]

#: Grid points per axis, by the number of fitted parameters.
POINTS_PER_AXIS = {1: 401, 2: 81, 3: 25, 4: 13, 5: 9}
#: Half-width of the first box, in Gauss-Newton standard errors.
BOX_HALF_WIDTH_SE = 4.0
#: Fewest cells the region must span along each axis before the box is shrunk.
MIN_CELLS = 8


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



def _settle(residuals, theta, axes_theta, scales, lower, upper, m, n, chi2_hat, level,
            noise_dof, scale_misfit, max_rounds):
    """Grow and shrink the grid until the region fits in it; the last grid's values."""
    d = theta.size
    z_lo = np.full(d, -BOX_HALF_WIDTH_SE)
    z_hi = np.full(d, BOX_HALF_WIDTH_SE)
    notes, shrinks, total = [], 0, 0
    for _ in range(max_rounds):
        zs, pts, clipped = _rotated_grid(theta, axes_theta, scales, z_lo, z_hi, m, lower,
                                         upper)
        chi2 = chi2_values(residuals, pts, n)
        total += pts.shape[0]
        chi2_min = min(chi2_hat, float(chi2.min()))
        if not math.isfinite(chi2_min):
            raise ValueError("no candidate of the space near the fit has a curve")
        dof = max(n - d, 1)
        scale = misfit_scale(chi2_min, dof, noise_dof) if scale_misfit else 1.0
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
    return pts, chi2, inside, chi2_min, limit, scale, total, notes


def _region_intervals(parameters, G, theta, pts, chi2, inside, limit, m, lower, upper):
    """{name: Interval}: each parameter's range over the region of the last grid."""
    d = theta.size
    shape = (m,) * d
    tiny = 1e-9 * (upper - lower)
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
    return intervals


def grid_intervals(residuals, theta, lower, upper, parameters, G, cov, n, chi2_hat, m, level,
                   noise_dof, scale_misfit, fit_is_minimum, max_rounds):
    """Intervals of ``parameters`` from the region of a settled grid.

    Parameters
    ----------
    residuals : callable
        ``(N, d) -> (N, n)`` residuals in units of the noise sd.
    theta : ndarray (d,)
        The fit, within the bounds.
    lower, upper : ndarray (d,)
        The bounds of the space.
    parameters : dict
        name -> callable ``(N, d) -> (N,)``.
    G : ndarray (n_parameters, d)
        Their gradients at the fit.
    cov : ndarray (d, d) or None
        Gauss-Newton covariance (the grid's axes; None: the coordinate axes).
    n : int
        Residuals per candidate.
    chi2_hat : float
        chi2 at the fit.
    m : int
        Grid points per axis.
    level, noise_dof, scale_misfit, fit_is_minimum, max_rounds
        As for :func:`._intervals.profile_intervals`.

    Returns
    -------
    intervals, chi2_min, limit, scale, grid_points, notes
    """
    axes_theta, scales = _principal_axes(cov, upper - lower)
    pts, chi2, inside, chi2_min, limit, scale, total, notes = _settle(
        residuals, theta, axes_theta, scales, lower, upper, m, n, chi2_hat, level, noise_dof,
        scale_misfit, max_rounds)
    if fit_is_minimum and chi2_hat > chi2_min + 1e-6 * max(1.0, chi2_min):
        notes.append(f"the grid found a lower chi2 ({chi2_min:.4g}) than the fit "
                     f"({chi2_hat:.4g}): the fit is not the minimum")
    intervals = _region_intervals(parameters, G, theta, pts, chi2, inside, limit, m, lower,
                                  upper)
    return intervals, chi2_min, limit, scale, total, notes
