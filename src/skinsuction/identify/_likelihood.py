"""The likelihood of a fit and what the intervals build on.

``chi2(theta) = sum (residual / sd)^2`` of whitened residuals, the threshold of a
level (:func:`interval_threshold`), the Birge ratio that widens it for a
significant misfit (:func:`misfit_scale`), the central-difference Jacobian and
the Gauss-Newton covariance, the gradients of the reported parameters and their
local correlation.  Shared by the profile intervals (:mod:`._intervals`) and the
Laplace intervals of the time curves (:mod:`._time_intervals`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import stats

__all__ = ["Interval", "LikelihoodIntervals", "interval_threshold", "misfit_scale",
           "chi2_values", "central_jacobian", "gauss_newton_covariance", "gradients",
           "correlation", "CHUNK_VALUES"]

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

    Parameters
    ----------
    level : float
        Confidence level, in (0, 1).
    noise_dof : float
        Degrees of freedom of the noise estimate (inf: known).

    Returns
    -------
    float

    Examples
    --------
    >>> round(interval_threshold(0.95), 3), round(interval_threshold(0.95, 20), 3)
    (3.841, 4.351)
    """
    if math.isinf(noise_dof):
        return float(stats.chi2.ppf(level, 1))
    return float(stats.f.ppf(level, 1, noise_dof))



def misfit_scale(chi2_min: float, dof: float, noise_dof: float = math.inf,
                 alpha: float = 0.01) -> float:
    """The Birge ratio chi2_min / dof where it is significantly above 1, else 1.

    Scaling whenever chi2_min > dof would widen the intervals of a correct model
    half the time (measured: 97 % coverage instead of 95 % with an estimated
    noise level); only a misfit that the noise does not explain at level
    ``alpha`` (the reduced chi2 against F(dof, noise_dof)) widens them.

    Parameters
    ----------
    chi2_min : float
        The fit's chi^2.
    dof : float
        Its degrees of freedom (points - parameters).
    noise_dof : float
        Degrees of freedom of the noise estimate (inf: known; then the reduced
        chi2 is compared with chi2(dof) / dof).
    alpha : float
        Significance of the misfit.

    Returns
    -------
    float
        ``chi2_min / dof`` if significant, else 1.

    Examples
    --------
    >>> misfit_scale(100.0, 100), round(misfit_scale(200.0, 100), 3)
    (1.0, 2.0)
    """
    ratio = chi2_min / dof
    crit = (stats.chi2.ppf(1 - alpha, dof) / dof if math.isinf(noise_dof)
            else stats.f.ppf(1 - alpha, dof, noise_dof))
    return float(ratio) if ratio > crit else 1.0



def chi2_values(residuals, theta, n_points):
    """chi2 of the candidates, CHUNK_VALUES curve values at a time.

    Parameters
    ----------
    residuals : callable
        ``(N, d) -> (N, n)`` residuals in units of the noise sd.
    theta : ndarray (N, d)
        The candidates.
    n_points : int
        n, the residuals of one candidate.

    Returns
    -------
    ndarray (N,)
        Sums of squares; +inf where a residual is not finite.
    """
    out = np.empty(theta.shape[0])
    chunk = max(16, CHUNK_VALUES // max(n_points, 1))
    for i in range(0, theta.shape[0], chunk):
        r = np.asarray(residuals(theta[i:i + chunk]), dtype=float)
        c = np.einsum("nt,nt->n", r, r)
        c[~np.isfinite(c)] = np.inf
        out[i:i + chunk] = c
    return out


def central_jacobian(residuals, theta, h, lower, upper) -> np.ndarray:
    """Jacobian of ``residuals`` at ``theta`` by central differences.

    Parameters
    ----------
    residuals : callable
        ``(N, d) -> (N, n)``; called once, with the 2 d stepped points.
    theta : ndarray (d,)
        Where, within the bounds.
    h : float or array_like (d,)
        The step of each coordinate either way, cut at the bounds.
    lower, upper : ndarray (d,)
        The bounds.

    Returns
    -------
    ndarray (n, d)
        Not finite where a stepped point has no residual.
    """
    d = theta.size
    h = np.broadcast_to(np.asarray(h, dtype=float), (d,))
    pts = []
    for a in range(d):
        lo, hi = theta.copy(), theta.copy()
        lo[a] = np.clip(theta[a] - h[a], lower[a], upper[a])
        hi[a] = np.clip(theta[a] + h[a], lower[a], upper[a])
        pts += [lo, hi]
    r = np.asarray(residuals(np.array(pts)), dtype=float)
    steps = np.array([pts[2 * a + 1][a] - pts[2 * a][a] for a in range(d)])
    return (r[1::2] - r[0::2]).T / steps


def gauss_newton_covariance(residuals, theta, lower, upper):
    """Covariance of theta (unit noise), ``(J^T J)^-1``, from a central-difference Jacobian.

    Parameters
    ----------
    residuals : callable
        ``(N, d) -> (N, n)`` residuals in units of the noise sd.
    theta : ndarray (d,)
        The fit.
    lower, upper : ndarray (d,)
        The bounds; the step is 1e-4 of their span.

    Returns
    -------
    ndarray (d, d) or None
        None if the Jacobian is not finite or J^T J singular.
    """
    J = central_jacobian(residuals, theta, 1e-4 * np.maximum(upper - lower, 1e-12), lower,
                         upper)
    if not np.all(np.isfinite(J)):
        return None
    try:
        cov = np.linalg.inv(J.T @ J)
    except np.linalg.LinAlgError:
        return None
    return cov if np.all(np.isfinite(cov)) and np.all(np.diag(cov) > 0) else None


def gradients(parameters, theta, lower, upper) -> np.ndarray:
    """d(parameter)/d(theta) at theta by central differences (1e-6 of the span).

    Parameters
    ----------
    parameters : dict
        name -> callable ``(N, d) -> (N,)``.
    theta : ndarray (d,)
    lower, upper : ndarray (d,)
        The bounds.

    Returns
    -------
    ndarray (n_parameters, d)
        0 where not finite.
    """
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


def correlation(cov, G, names) -> dict:
    """Local (Gauss-Newton) correlation of every pair of parameters.

    Parameters
    ----------
    cov : ndarray (d, d) or None
        Covariance of theta.
    G : ndarray (n_parameters, d)
        The parameters' gradients (:func:`gradients`).
    names : list of str
        The parameters' names, in the order of G's rows.

    Returns
    -------
    dict
        ``{"a,b": r}`` (None where not finite); empty without a covariance.
    """
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
