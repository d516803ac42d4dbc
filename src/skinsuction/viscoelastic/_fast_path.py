"""The fast path: the elastic equilibrium curve driven by an effective load.

In linear viscoelasticity with one relaxation function for every modulus,
``G(t) = G_inf phi(t)`` (shear and bulk alike: ``branches="full"``), the
correspondence principle gives the displacement under a load history ``p(t)`` as
the elastic one (moduli ``G_inf``) under the **effective load**

    p_eff(t) = int_0^t psi(t - s) dp(s),     psi = J(t) / J(inf) = G_inf J(t),

the load passed through the normalised creep compliance ``psi`` (from
``1/(1 + sum g)`` at t = 0 to 1), the inverse of ``phi`` under Stieltjes
convolution (``s Phi(s) s Psi(s) = 1``; :meth:`Prony.retardation`). The fast path
takes the same for the finite-strain model: ``M(t) = M_el(p_eff(t))``, with
``M_el`` the elastic (long-time) equilibrium curve. It is exact in the linear
limit; its error at finite strain is measured (``benchmarks/viscoelastic_fast_path.py``,
``docs/viscoelasticity.md``). Since ``psi`` rises from ``psi(0) > 0`` to 1,
``0 <= p_eff <= max p`` for any suction ``p >= 0``: the elastic curve up to the
largest suction suffices.
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import CubicSpline

from ..model import ParameterError
from ._prony import Prony, layer_spectra


def effective_pressure(prony, times_s, pressures_mbar):
    """``p_eff(t) = int psi(t - s) dp(s)`` at the given times, exact for a suction
    piecewise linear between them (a nonzero first value is a step at the first time).

    With ``psi(t) = 1 - sum_j c_j exp(-t/lambda_j)``, ``p_eff = p - sum_j c_j y_j``
    where ``y_j = int exp(-(t-s)/lambda_j) dp(s)`` is updated exactly over each
    linear piece: ``y <- e y + rate lambda (1 - e)``, ``e = exp(-dt/lambda)``.

    Examples
    --------
    A step of 100 mbar on the standard linear solid (g = 1, tau = 0.1 s): 50 mbar
    at once, then creep with the retardation time tau (1 + g) = 0.2 s.

    >>> p = effective_pressure(Prony([1.0], [0.1]), [0.0, 0.2, 10.0], [100.0, 100.0, 100.0])
    >>> [round(float(v), 3) for v in p]
    [50.0, 81.606, 100.0]
    """
    t = np.asarray(times_s, dtype=float)
    p = np.asarray(pressures_mbar, dtype=float)
    if t.shape != p.shape or np.any(np.diff(t) <= 0):
        raise ParameterError("times_s must increase strictly, one pressure each")
    c, lam = prony.retardation()
    y = np.full(c.shape, p[0])
    out = np.empty_like(p)
    out[0] = p[0] - c @ y
    for k in range(1, len(t)):
        dt = t[k] - t[k - 1]
        rate = (p[k] - p[k - 1]) / dt
        e = np.exp(-dt / lam)
        y = e * y - rate * lam * np.expm1(-dt / lam)
        out[k] = p[k] - c @ y
    return out


def fast_history(elastic_curve, prony, times_s, pressures_mbar):
    """Apex deflection against time by the fast path: ``M_el(p_eff(t))``.

    Parameters
    ----------
    elastic_curve : Curve or (pressures_mbar, deflection_mm)
        The long-time (X1) elastic curve, up to at least the largest suction
        (its converged points are used; a cubic spline between them).
    prony : Prony
        The spectrum, shared by both layers (the fast path has no per-layer form:
        a dict with two different spectra is refused).
    times_s, pressures_mbar : array_like
        The history (piecewise linear between the points).

    Returns
    -------
    ndarray
        Deflection (mm) at each time.

    Examples
    --------
    >>> from skinsuction.model import Skin, simulate
    >>> from skinsuction.viscoelastic import Prony
    >>> curve = simulate(Skin.two_layer(0.08, 4.1e-3), pressures_mbar=range(0, 41, 4),
    ...                  mesh={"refinement": 0.5})
    >>> m = fast_history(curve, Prony([1.0], [0.2]), [0, 0.001, 0.2, 1.0, 3.0], [0, 40, 40, 40, 40])
    >>> [round(float(v / m[-1]), 2) for v in m[1:]]
    [0.5, 0.69, 0.96, 1.0]
    """
    dermis, hypodermis = layer_spectra(prony)
    if dermis != hypodermis:
        raise ParameterError("the fast path takes one spectrum for both layers")
    if hasattr(elastic_curve, "pressure_mbar"):
        p_el, m_el = elastic_curve.pressure_mbar, elastic_curve.deflection_mm
    else:
        p_el, m_el = elastic_curve
    p_el, m_el = np.asarray(p_el, float), np.asarray(m_el, float)
    ok = np.isfinite(m_el)
    p_el, m_el = p_el[ok], m_el[ok]
    p_eff = effective_pressure(dermis, times_s, pressures_mbar)
    if p_eff.max() > p_el.max() * (1 + 1e-12) or p_eff.min() < p_el.min() - 1e-12:
        raise ParameterError(
            f"the elastic curve covers {p_el.min():g}-{p_el.max():g} mbar; the effective "
            f"load reaches {p_eff.min():g}-{p_eff.max():g} mbar"
        )
    return CubicSpline(p_el, m_el)(np.clip(p_eff, p_el.min(), p_el.max()))
