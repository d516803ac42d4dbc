"""Statistics of the diagnosis: systematic-misfit test, BIC, wording.

The noise level (from replicates or differences) lives in :mod:`skinsuction.noise`.

Systematic misfit
    The residuals of a correct model are noise: white along the pressure.  A
    missing effect leaves a smooth pattern.  The test projects the residuals of
    each probe on Legendre polynomials of degree 0..K in the pressure (K = 4 by
    default: offset, slope, curvature and two more bends) and compares the
    energy of that smooth part with the noise:
    ``F = (||P e||^2 / k) / sigma^2 ~ F(k, nu)`` (``nu = inf`` for a noise level
    given by the user).  Under the model the fitted parameters have already
    absorbed some smooth directions, so the test is slightly conservative.

BIC
    With the noise level fixed at its estimate, ``-2 ln L = chi^2 + const`` and
    ``BIC = chi^2 + k ln n``, ``chi^2 = sum (residual / sigma)^2``; the
    difference to the baseline is ``delta_BIC = delta chi^2 + delta k ln n``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import stats

from skinsuction.noise import (  # noqa: F401  (re-exported)
    NoiseEstimate,
    difference_weights,
    noise_from_differences,
    noise_from_replicates,
)

__all__ = [
    "NoiseEstimate",
    "difference_weights",
    "noise_from_differences",
    "noise_from_replicates",
    "MisfitTest",
    "misfit_test",
    "bic",
    "describe_residuals",
]


# ---------------------------------------------------------------- misfit test
@dataclass(frozen=True)
class MisfitTest:
    """Smooth-residual test of one fit (see the module docstring)."""

    statistic: float  # F
    dof: tuple  # (k, nu)
    p_value: float
    alpha: float
    per_probe: dict  # probe -> {"F", "p_value", "smooth_um", "max_abs_smooth_um"}

    @property
    def significant(self) -> bool:
        return self.p_value < self.alpha

    def to_dict(self) -> dict:
        return {"F": self.statistic, "dof": [self.dof[0], None if math.isinf(self.dof[1])
                                             else self.dof[1]],
                "p_value": self.p_value, "alpha": self.alpha,
                "systematic": self.significant,
                "per_probe": {f"{p:g}": {k: v for k, v in d.items() if k != "smooth_um"}
                              for p, d in self.per_probe.items()}}


def _legendre_basis(p, degree):
    p = np.asarray(p, dtype=float)
    lo, hi = p.min(), p.max()
    x = 2 * (p - lo) / ((hi - lo) or 1.0) - 1
    B = np.polynomial.legendre.legvander(x, degree)
    q, _ = np.linalg.qr(B)
    return q


def _f_sf(f, k, nu):
    if math.isinf(nu):
        return float(stats.chi2.sf(f * k, k))
    return float(stats.f.sf(f, k, nu))


def misfit_test(residuals: dict, sigma_um: dict, noise_dof: float, degree: int = 4,
                alpha: float = 0.01) -> MisfitTest:
    """Test the residuals for a smooth pattern beyond the noise.

    Parameters
    ----------
    residuals : dict probe -> (pressure_mbar, residual_um)
    sigma_um : dict probe -> noise sd of the fitted points (µm)
    noise_dof : float
        Degrees of freedom of the noise estimate (inf if known).
    degree : int
        Highest Legendre degree of the smooth part, per probe.
    alpha : float
        Significance level.
    """
    total, k_total, per = 0.0, 0, {}
    for probe, (p, e) in residuals.items():
        e = np.asarray(e, dtype=float)
        deg = min(int(degree), len(e) - 2)
        q = _legendre_basis(p, deg)
        coef = q.T @ e
        smooth = q @ coef
        energy = float((coef ** 2).sum()) / sigma_um[probe] ** 2
        k = q.shape[1]
        per[probe] = {"F": energy / k, "p_value": _f_sf(energy / k, k, noise_dof),
                      "smooth_um": smooth, "max_abs_smooth_um": float(np.abs(smooth).max()),
                      "rms_um": float(np.sqrt(np.mean(e ** 2)))}
        total += energy
        k_total += k
    f = total / k_total
    return MisfitTest(f, (k_total, noise_dof), _f_sf(f, k_total, noise_dof), alpha, per)


def bic(chi2: float, n_params: int, n_points: int) -> float:
    """Bayesian information criterion with the noise level fixed: chi^2 + k ln n."""
    return float(chi2 + n_params * math.log(n_points))


# ---------------------------------------------------------------- wording
def _ranges(p, mask):
    """Contiguous pressure ranges (lo, hi) where mask is True."""
    out, start = [], None
    for i, m in enumerate(mask):
        if m and start is None:
            start = i
        if (not m or i == len(mask) - 1) and start is not None:
            end = i if m else i - 1
            out.append((float(p[start]), float(p[end])))
            start = None
    return out


def _fmt_range(lo, hi):
    return f"{lo:g} mbar" if lo == hi else f"{lo:g}-{hi:g} mbar"


def describe_residuals(test: MisfitTest, residuals: dict, sigma_um: dict) -> str:
    """Plain-language description of the residual pattern (measured - simulated).

    Names the probes whose residuals carry a smooth pattern, the pressure ranges
    where the model gives too little (measured above simulated) or too much
    deflection by more than one noise sd of the fitted points, the size of the
    pattern in µm and in noise sd, and its curvature over the pressure.
    """
    if not test.significant:
        worst = max(test.per_probe.values(), key=lambda d: d["F"])
        return (f"The residuals are consistent with the noise (smooth-pattern test "
                f"p = {test.p_value:.2g}); largest smooth pattern "
                f"{worst['max_abs_smooth_um']:.2g} µm.")
    parts = []
    for probe in sorted(residuals):
        d = test.per_probe[probe]
        p, _ = residuals[probe]
        p = np.asarray(p, dtype=float)
        s = d["smooth_um"]
        sig = sigma_um[probe]
        if d["p_value"] >= test.alpha and d["max_abs_smooth_um"] < 2 * sig:
            parts.append(f"{probe:g} mm probe: no clear pattern (p = {d['p_value']:.2g}).")
            continue
        under = _ranges(p, s > sig)
        over = _ranges(p, s < -sig)
        bits = []
        if under:
            bits.append("too little deflection (measured above simulated) at "
                        + ", ".join(_fmt_range(*r) for r in under)
                        + f", by up to {s.max():.1f} µm")
        if over:
            bits.append("too much deflection (measured below simulated) at "
                        + ", ".join(_fmt_range(*r) for r in over)
                        + f", by up to {-s.min():.1f} µm")
        if not bits:
            bits.append(f"a smooth pattern below one noise sd ({sig:.2g} µm) everywhere, "
                        "but consistent over the pressures")
        # curvature of the smooth residual: sign of its quadratic trend
        c2 = np.polyfit((p - p.mean()) / (np.ptp(p) or 1), s, 2)[0]
        amp = d["max_abs_smooth_um"]
        if abs(c2) * 0.25 > 0.3 * amp:
            if c2 < 0:
                shape = ("the residual is concave (arch-shaped) over the pressure: the "
                         "measured curve bends over (stiffens) more than the model's")
            else:
                shape = ("the residual is convex (U-shaped) over the pressure: the "
                         "measured curve bends over (stiffens) less than the model's")
        else:
            slope = np.polyfit(p, s, 1)[0]
            shape = ("the residual grows with the pressure" if slope > 0
                     else "the residual falls with the pressure")
        parts.append(f"{probe:g} mm probe: the model gives " + "; ".join(bits)
                     + f" ({amp / sig:.1f} noise sd); {shape} "
                       f"(smooth-pattern test p = {d['p_value']:.2g}).")
    return (f"Systematic misfit (smooth-pattern test p = {test.p_value:.2g}). "
            + " ".join(parts))
