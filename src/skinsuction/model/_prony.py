"""A relaxation spectrum (Prony series) over the long-time hyperelastic moduli.

Convention (the issue's): the moduli X1, X2 of a layer are its **long-time
(equilibrium)** moduli; a Prony term ``(g_i, tau_i)`` adds an over-stress branch
of moduli ``g_i X1, g_i X2`` that relaxes with time constant ``tau_i``. The
normalised relaxation function is

    phi(t) = 1 + sum_i g_i exp(-t / tau_i),      phi(inf) = 1,

so the instantaneous moduli are ``X1 (1 + sum g_i)``. Any ``g_i >= 0`` is
allowed (no upper bound: the fractions are of the long-time modulus, not of the
instantaneous one).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._curve import ParameterError


@dataclass(frozen=True)
class Prony:
    """Relaxation spectrum of one layer: fractions ``g`` of the long-time moduli
    and relaxation times ``tau_s``.

    Parameters
    ----------
    g : sequence of float
        Fractions g_i >= 0 of the long-time moduli (X1 long-time, X1 (1 + sum g)
        instantaneous).
    tau_s : sequence of float
        Relaxation times tau_i > 0 in seconds, one per fraction.

    Examples
    --------
    >>> spectrum = Prony(g=[0.5, 0.3], tau_s=[0.01, 0.5])
    >>> spectrum.instantaneous_factor
    1.8
    >>> [round(float(v), 4) for v in spectrum.relaxation([0.0, 1e9])]
    [1.8, 1.0]
    >>> round(float(spectrum.creep(0.0)), 4), round(float(spectrum.creep(1e9)), 4)
    (0.5556, 1.0)
    """

    g: tuple = ()
    tau_s: tuple = ()

    def __post_init__(self):
        g = tuple(float(v) for v in np.atleast_1d(np.asarray(self.g, dtype=float)))
        tau = tuple(float(v) for v in np.atleast_1d(np.asarray(self.tau_s, dtype=float)))
        if len(g) != len(tau):
            raise ParameterError(f"Prony: {len(g)} fractions g but {len(tau)} times tau_s")
        if not all(np.isfinite(v) and v >= 0 for v in g):
            raise ParameterError(f"Prony: every g must be finite and >= 0, not {g}")
        if not all(np.isfinite(v) and v > 0 for v in tau):
            raise ParameterError(f"Prony: every tau_s must be finite and > 0, not {tau}")
        object.__setattr__(self, "g", g)
        object.__setattr__(self, "tau_s", tau)

    @classmethod
    def elastic(cls):
        """No relaxation (g = 0): the purely elastic model."""
        return cls((), ())

    @property
    def terms(self):
        """Number of Prony terms."""
        return len(self.g)

    @property
    def instantaneous_factor(self):
        """``1 + sum g_i``: instantaneous over long-time moduli."""
        return 1.0 + float(sum(self.g))

    def relaxation(self, t_s):
        """Normalised relaxation function ``phi(t) = 1 + sum g_i exp(-t/tau_i)``."""
        t = np.asarray(t_s, dtype=float)
        out = np.ones_like(t)
        for g, tau in zip(self.g, self.tau_s):
            out = out + g * np.exp(-t / tau)
        return out

    def retardation(self):
        """The creep function of the spectrum as a Prony series of its own.

        The normalised creep compliance ``psi(t) = J(t) / J(inf)`` is the inverse
        of ``phi`` under Stieltjes convolution, ``s Phi(s) * s Psi(s) = 1`` in
        the Laplace domain. With ``a_i = 1/tau_i``,

            s Psi(s) = D(s) / N(s),  D = prod (s + a_i),
            N = D + sum_i g_i s prod_{k != i} (s + a_k),

        whose poles ``-b_j`` (the roots of N, real, negative, one between each
        pair of the a_i) give ``psi(t) = 1 - sum_j c_j exp(-b_j t)`` with
        ``c_j = D(-b_j) / (b_j N'(-b_j))``.

        Returns
        -------
        c : ndarray
            Weights c_j (sum: ``1 - 1/(1 + sum g)``).
        lam_s : ndarray
            Retardation times ``lambda_j = 1/b_j`` in seconds.

        Examples
        --------
        One term (the standard linear solid): ``c = g/(1+g)``, ``lambda = tau (1+g)``.

        >>> c, lam = Prony(g=[1.0], tau_s=[0.2]).retardation()
        >>> round(float(c[0]), 6), round(float(lam[0]), 6)
        (0.5, 0.4)
        """
        live = [(g, tau) for g, tau in zip(self.g, self.tau_s) if g > 0]
        if not live:
            return np.zeros(0), np.zeros(0)
        a = np.array([1.0 / tau for _, tau in live])
        gs = np.array([g for g, _ in live])
        D = np.poly(-a)  # coefficients of prod (s + a_i), highest first
        N = D.copy()
        for i in range(len(a)):
            term = np.polymul([gs[i], 0.0], np.poly(-np.delete(a, i)))
            N = np.polyadd(N, term)
        roots = np.roots(N)
        if np.max(np.abs(roots.imag)) > 1e-9 * np.max(np.abs(roots)):
            raise ArithmeticError("complex retardation rates: the spectrum is not a Prony series")
        b = np.sort(-roots.real)
        c = np.polyval(D, -b) / (b * np.polyval(np.polyder(N), -b))
        return c, 1.0 / b

    def creep(self, t_s):
        """Normalised creep compliance ``psi(t) = J(t)/J(inf)``: from
        ``1/(1 + sum g)`` at t = 0 to 1 (see :meth:`retardation`)."""
        t = np.asarray(t_s, dtype=float)
        c, lam = self.retardation()
        out = np.ones_like(t)
        for cj, lj in zip(c, lam):
            out = out - cj * np.exp(-t / lj)
        return out
