"""The noise level of measured suction curves, from replicates or from the curve itself.

Noise level
    *From replicates* (several curves of a probe at the same pressures): the
    pooled variance of the replicates about their pressure-wise mean,
    ``s^2 = sum (y_rt - ybar_t)^2 / sum (R - 1)``, with ``sum (R - 1)``
    degrees of freedom; the diagnosis fits the mean curve, whose noise is
    ``s / sqrt(R)``.
    *From the data* (one curve per probe): difference-based estimator.  A
    measured curve M(p) is smooth, so a difference of order k (weights that
    annihilate every polynomial of degree < k, normalised to unit norm) of k + 1
    neighbouring points removes the curve and keeps the noise:
    ``d_t = c_t . y``, ``E d_t^2 = sigma^2``.  With k = 3 a quadratic trend
    over four points is removed exactly (the FE curves have |d^3 M| below
    0.1 µm at 2 mbar steps, against a noise of µm).  The weights are computed
    for the actual pressures, so uneven steps are fine.  The effective degrees
    of freedom of ``sigma^2 = mean d_t^2`` (neighbouring d_t overlap) are
    exact for Gaussian noise: ``nu = n_d^2 / ||C C^T||_F^2``.

Examples
--------
>>> import numpy as np
>>> p = np.arange(0.0, 500.0, 0.5)
>>> rng = np.random.default_rng(1)
>>> m = 0.8 * (p / 500) ** 0.7 + rng.normal(0, 2e-3, p.size)  # 2 µm noise
>>> round(noise_from_differences([(p, m)]).sd_um, 1)
2.0
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["NoiseEstimate", "difference_weights", "noise_from_differences", "noise_from_replicates"]


@dataclass(frozen=True)
class NoiseEstimate:
    """Noise of one measured deflection (µm), how it was estimated and its dof."""

    sd_um: float
    method: str  # "replicates", "differences" or "given"
    dof: float
    detail: dict

    def to_dict(self) -> dict:
        return {"sd_um": self.sd_um, "method": self.method,
                "dof": None if math.isinf(self.dof) else self.dof, **self.detail}


def difference_weights(x, order: int = 3) -> np.ndarray:
    """Rows of unit-norm weights that annihilate polynomials of degree < ``order``.

    Row t acts on ``y[t : t + order + 1]``; for equal steps it is the binomial
    difference scaled to unit norm.

    >>> difference_weights([0, 1, 2, 3], order=3).round(4).tolist()
    [[-0.2236, 0.6708, -0.6708, 0.2236]]
    """
    x = np.asarray(x, dtype=float)
    n, k = x.size, int(order)
    if n < k + 1:
        return np.empty((0, k + 1))
    # k+1 points leave one weight vector: the k-th divided difference,
    # c_j = 1 / prod_{i != j} (x_j - x_i), each window scaled to unit span first
    idx = np.arange(n - k)[:, None] + np.arange(k + 1)
    xs = x[idx]
    span = np.ptp(xs, axis=1, keepdims=True)
    xs = (xs - xs.mean(axis=1, keepdims=True)) / np.where(span > 0, span, 1.0)
    diff = xs[:, :, None] - xs[:, None, :]
    diff[:, np.arange(k + 1), np.arange(k + 1)] = 1.0
    c = 1.0 / np.prod(diff, axis=2)
    c *= np.sign(c[:, -1:]) / np.linalg.norm(c, axis=1, keepdims=True)
    return c


def _gram_frobenius2(c) -> float:
    """``||C C^T||_F^2`` of the banded difference matrix whose row t is ``c[t]`` at
    columns t .. t + k: only rows at most k apart overlap, so O(n k^2), not O(n^2)."""
    n, w = c.shape
    total = float(np.sum(np.sum(c * c, axis=1) ** 2))
    for lag in range(1, min(w, n)):
        # row t against row t + lag: c[t, lag:] . c[t + lag, :w - lag]
        g = np.sum(c[:-lag, lag:] * c[lag:, :w - lag], axis=1)
        total += 2.0 * float(np.sum(g ** 2))
    return total


def noise_from_differences(curves, order: int = 3) -> NoiseEstimate:
    """Noise sd of single deflections from differences of smooth curves.

    Parameters
    ----------
    curves : iterable of (pressure_mbar, deflection_mm)
        The measured curves (p = 0 points included or not).
    """
    sq, blocks = [], []
    for p, m in curves:
        c = difference_weights(p, order)
        if not len(c):
            continue
        idx = np.arange(len(c))[:, None] + np.arange(order + 1)
        d = (c * np.asarray(m, dtype=float)[idx]).sum(axis=1)
        sq.append(d ** 2)
        blocks.append(_gram_frobenius2(c))  # ||C C^T||_F^2 of this curve, for the dof
    if not sq:
        raise ValueError(f"the curves are too short to estimate the noise "
                         f"(need > {order} points)")
    sq = np.concatenate(sq)
    n_d = sq.size
    frob = sum(blocks)
    dof = n_d ** 2 / frob
    sd_um = 1e3 * math.sqrt(sq.mean())
    return NoiseEstimate(sd_um, "differences", dof,
                         {"order": order, "n_differences": int(n_d)})


def noise_from_replicates(groups) -> NoiseEstimate:
    """Pooled noise sd (µm) of replicate curves measured at the same pressures.

    Parameters
    ----------
    groups : iterable of ndarray (R, u)
        For each probe, its R >= 2 replicate curves (mm) at common pressures.
    """
    ss, dof, sizes = 0.0, 0, []
    for y in groups:
        y = np.asarray(y, dtype=float)
        if y.shape[0] < 2:
            continue
        ss += float(((y - y.mean(axis=0)) ** 2).sum())
        dof += y.shape[1] * (y.shape[0] - 1)
        sizes.append(int(y.shape[0]))
    if dof == 0:
        raise ValueError("no probe has two or more replicate curves")
    return NoiseEstimate(1e3 * math.sqrt(ss / dof), "replicates", float(dof),
                         {"replicates": sizes})
