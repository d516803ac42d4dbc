"""The viscoelastic fast path on the scale-free space, vectorised over candidates.

A candidate ``theta = (log10 X1d, log10 X1h/X1d, log10 g_1, log10 tau_1[, log10 g_2,
log10 tau_2])`` (long-time moduli in MPa, tau in s; no Prony terms: the elastic
model) gives the deflection of a time curve as ``M_el(p_eff(t))``
(:mod:`skinsuction.viscoelastic`, ``docs/viscoelasticity.md``):

* ``p_eff(t) = p(t) - sum_j c_j y_j(t)`` with the spectrum's creep function
  ``psi = 1 - sum_j c_j exp(-t/lambda_j)`` (:func:`retardation`, closed forms for
  one and two terms), updated exactly over each linear piece of the suction
  (:func:`effective_pressures`);
* ``M_el`` at ``(X1d, X1h)`` from the space's neo-Hookean rays: the ray at
  ``r = X1h/X1d`` (:meth:`skinsuction.space.RayInterpolant.combined_logs`) read
  along its load (:class:`skinsuction.space.LoadAxis`) at ``p_eff X1d_ref / X1d`` (the scaling law), exactly
  as :class:`~skinsuction.space.RayInterpolant` reads fixed pressures: each
  candidate has its own p_eff, so the rays are read at it directly.

The suction that drives the model is the file's, cleaned of its sensor noise
(:func:`clean_pressure`): 2 mbar of noise on a 400 mbar step would otherwise move
the model by about 0.5 % of the deflection at every sample.

Examples
--------
One term: ``c = g/(1+g)``, ``lambda = tau (1+g)``, as :meth:`Prony.retardation`.

>>> import numpy as np
>>> c, lam = retardation(np.log10([[1.0, 0.2]]))
>>> round(float(c[0, 0]), 6), round(float(lam[0, 0]), 6)
(0.5, 0.4)
>>> t = np.array([0.0, 0.2, 10.0]); p = np.full(3, 100.0)
>>> [round(float(v), 3) for v in effective_pressures(np.log10([[1.0, 0.1]]), t, p)[0]]
[50.0, 81.606, 100.0]
"""

from __future__ import annotations

import math

import numpy as np

from skinsuction.space import LoadAxis, RayInterpolant, reference_pressure

__all__ = ["G_BOUNDS", "TAU_BOUNDS_S", "retardation", "effective_pressures", "clean_pressure",
           "ElasticRays", "theta_names"]

#: Range of each Prony fraction g_i searched (fractions of the long-time modulus).
G_BOUNDS = (1e-3, 5.0)
#: Range of each relaxation time searched (s): the literature's 10 ms and 0.1-1 s
#: with a decade to spare either side.
TAU_BOUNDS_S = (1e-3, 10.0)


def theta_names(terms: int, cause=None) -> list:
    """Names of the coordinates of theta for ``terms`` Prony terms (and an elastic
    cause's axis coordinate before them, :meth:`skinsuction.space.Cause.to_axis`).

    >>> theta_names(1)
    ['log10 X1d', 'log10 X1h/X1d', 'log10 g_1', 'log10 tau_1']
    """
    out = ["log10 X1d", "log10 X1h/X1d"]
    if cause is not None:
        out.append(f"{cause.name} axis")
    for i in range(1, terms + 1):
        out += [f"log10 g_{i}", f"log10 tau_{i}"]
    return out


def retardation(spectrum):
    """``(c, lam)``, (N, J) each: the creep function of N spectra.

    ``spectrum`` (N, 2 J) holds ``log10 g_i, log10 tau_i`` per term (J = 0, 1 or 2).
    ``psi(t) = 1 - sum_j c_j exp(-t / lam_j)`` (see :meth:`Prony.retardation`, here in
    closed form so that thousands of candidates cost one vector operation).
    """
    s = np.atleast_2d(np.asarray(spectrum, dtype=float))
    terms = s.shape[1] // 2
    g, tau = 10.0 ** s[:, 0::2], 10.0 ** s[:, 1::2]
    if terms == 0:
        return np.zeros((s.shape[0], 0)), np.ones((s.shape[0], 0))
    if terms == 1:
        return g / (1.0 + g), tau * (1.0 + g)
    if terms != 2:
        raise ValueError(f"one or two Prony terms, not {terms}")
    a1, a2 = 1.0 / tau[:, 0], 1.0 / tau[:, 1]
    g1, g2 = g[:, 0], g[:, 1]
    # N(s) = (s + a1)(s + a2) + g1 s (s + a2) + g2 s (s + a1) = A s^2 + B s + C
    A, B, C = 1.0 + g1 + g2, a1 + a2 + g1 * a2 + g2 * a1, a1 * a2
    root = np.sqrt(np.maximum(B * B - 4.0 * A * C, 0.0))
    b = np.stack([(B - root) / (2.0 * A), (B + root) / (2.0 * A)], axis=1)  # -roots of N
    # the smaller root without cancellation: b_small = 2C / (B + root)
    b[:, 0] = 2.0 * C / (B + root)
    d_at = (a1[:, None] - b) * (a2[:, None] - b)  # D(-b)
    n_prime = -2.0 * A[:, None] * b + B[:, None]  # N'(-b)
    return d_at / (b * n_prime), 1.0 / b


def effective_pressures(spectrum, times_s, pressure_mbar, breaks=None):
    """``p_eff`` (N, T) of N spectra under one suction, piecewise linear between samples.

    Exact for a suction linear between its samples (a nonzero first value is a step
    at the first time), as :func:`skinsuction.viscoelastic.effective_pressure`.
    ``breaks`` (sorted sample indices, first 0 and last T - 1): where the slope of
    the suction changes; the state is carried from break to break and the samples
    between are evaluated in closed form, so a mode-1 curve (constant suction over
    its holds) costs a few dozen vector operations whatever its length.
    """
    c, lam = retardation(spectrum)
    t = np.asarray(times_s, dtype=float)
    p = np.asarray(pressure_mbar, dtype=float)
    n, T = c.shape[0], t.size
    out = np.broadcast_to(p, (n, T)).copy()
    if c.shape[1] == 0:
        return out
    if breaks is None:
        breaks = pressure_breaks(t, p)
    y = np.broadcast_to(p[0], c.shape).copy()  # state y_j at the current break
    out[:, 0] -= (c * y).sum(axis=1)
    for a, b in zip(breaks[:-1], breaks[1:]):
        rate = (p[b] - p[a]) / (t[b] - t[a])
        dt = t[a + 1:b + 1] - t[a]  # (k,)
        e = np.exp(-dt[None, None, :] / lam[:, :, None])  # (N, J, k)
        ys = e * y[:, :, None] + rate * lam[:, :, None] * (1.0 - e)
        out[:, a + 1:b + 1] -= np.einsum("nj,njk->nk", c, ys)
        y = ys[:, :, -1]
    return out


def pressure_breaks(times_s, pressure_mbar, rtol: float = 1e-9) -> np.ndarray:
    """Sample indices where the slope of a piecewise linear suction changes (with
    the first and the last sample).

    >>> pressure_breaks([0, 1, 2, 3, 4], [0, 10, 10, 10, 0]).tolist()
    [0, 1, 3, 4]
    """
    t = np.asarray(times_s, dtype=float)
    p = np.asarray(pressure_mbar, dtype=float)
    slope = np.diff(p) / np.diff(t)
    tol = rtol * max(float(np.abs(slope).max(initial=0.0)), 1.0)
    kinks = np.flatnonzero(np.abs(np.diff(slope)) > tol) + 1
    return np.unique(np.concatenate([[0], kinks, [t.size - 1]])).astype(int)


def _moving_average(x, width):
    """Centred moving average, the window shrinking symmetrically at the ends (a
    straight line passes unchanged)."""
    n, h = x.size, width // 2
    out = np.empty_like(x)
    csum = np.concatenate([[0.0], np.cumsum(x)])
    for i in range(n):
        k = min(h, i, n - 1 - i)
        out[i] = (csum[i + k + 1] - csum[i - k]) / (2 * k + 1)
    return out


def clean_pressure(curve) -> tuple:
    """``(pressure, note)``: the suction that drives the model, without sensor noise.

    Per cycle of the loader (:class:`skinsuction.measured.TimeCurve`): the hold of a
    step is its level (the median of the hold), the rise and the release of a step
    are the samples as read (a switch lasts a sample or two), a ramp's rise and
    release are the least-squares lines through them; what is off (before the first
    cycle and each off time) is the median of its samples; any other cycle is a
    centred 5-sample moving average within each phase.  Never below 0.
    """
    t = np.asarray(curve.time_s, dtype=float)
    raw = np.asarray(curve.pressure_mbar, dtype=float)
    p = raw.copy()
    off_spans = []
    start = 0
    for c in curve.cycles:
        off_spans.append((start, c.onset))
        start = c.off if c.off is not None else t.size
        hold = slice(c.hold_start, c.hold_end + 1)
        rise, release = slice(c.onset, c.hold_start), slice(c.release, start)
        if c.kind == "step":
            p[hold] = float(np.median(raw[hold]))
        elif c.kind == "ramp":
            p[hold] = float(np.median(raw[hold]))
            for part in (rise, release):
                if part.stop - part.start >= 3:
                    k = np.polyfit(t[part], raw[part], 1)
                    p[part] = np.clip(np.polyval(k, t[part]), 0.0, c.level_mbar)
        else:
            for part in (rise, hold, release):
                if part.stop > part.start:
                    p[part] = _moving_average(raw[part], 5)
    off_spans.append((start, t.size))
    for a, b in off_spans:
        if b > a:
            p[a:b] = float(np.median(raw[a:b]))
    p = np.maximum(p, 0.0)
    kinds = sorted({c.kind for c in curve.cycles})
    note = ("suction cleaned of sensor noise: holds of steps at their median level, off "
            "times at their median, ramps as fitted lines, switches as read "
            f"(cycles: {', '.join(kinds) or 'none'}); residual sd of the cleaning "
            f"{float(np.std(raw - p)):.2g} mbar")
    return p, note


class ElasticRays:
    """``M_el(X1d, X1h, p)`` of one probe from the scale-free space, at per-candidate
    pressures.

    Parameters
    ----------
    space : RaySpace
        The neo-Hookean ray space (e.g. ``load_space().probe(6).space``), or a
        cause's (e.g. strain stiffening: the nonlinear elastic curve of that skin).
    probe_mm : float
    p_max_mbar : float
        The largest suction of the curve: it raises the lowest X1d searched to
        ``p_max / load_max`` (and a suction beyond the space's reach raises the
        :class:`ValueError` of :class:`RayInterpolant`).

    Examples
    --------
    >>> import numpy as np
    >>> from skinsuction.space import load_space
    >>> rays = load_space().probe(6).space
    >>> el = ElasticRays(rays, 6.0, 400.0)
    >>> theta = np.array([[np.log10(0.1), np.log10(0.05)]])
    >>> m = el(theta, np.array([[100.0, 400.0]]))
    >>> ref = RayInterpolant(rays, 6.0, [100.0, 400.0])(theta)
    >>> bool(np.allclose(m, ref, rtol=1e-12))
    True
    """

    def __init__(self, space, probe_mm: float, p_max_mbar: float):
        self._interp = RayInterpolant(space, probe_mm, [0.0, float(p_max_mbar)])
        self.lower, self.upper = self._interp.lower, self._interp.upper
        self.x1d_ref = float(space.spec.x1d_ref)
        self._load = LoadAxis(space.spec.pressures_mbar)
        self.load_max = float(space.spec.load_max)
        self.cause = space.cause

    def __call__(self, theta, pressure_mbar) -> np.ndarray:
        """Deflections (N, T) in mm of candidates ``theta (N, d)`` (``d`` = 2, or 3 with
        the cause's axis coordinate of a cause's space) at ``pressure (N, T)``; NaN
        where a ray stopped before that load (or outside the space)."""
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        q = reference_pressure(np.maximum(pressure_mbar, 0.0), (10.0 ** theta[:, 0])[:, None],
                               self.x1d_ref)
        # the space's NaN policy across rays, its interpolant along the load
        return self._load.evaluate(
            self._interp.combined_logs(theta, loads=self._load.loads_for(q)), q)


def prony_of(theta, start: int = 2) -> tuple:
    """``(g, tau_s)`` lists of one theta (its spectrum from index ``start``), terms
    sorted by tau."""
    theta = np.asarray(theta, dtype=float).reshape(-1)
    g, tau = 10.0 ** theta[start::2], 10.0 ** theta[start + 1::2]
    order = np.argsort(tau)
    return [float(v) for v in g[order]], [float(v) for v in tau[order]]


def sort_terms(theta, start: int = 2) -> np.ndarray:
    """theta with its Prony terms (from index ``start``) in the order of increasing tau."""
    theta = np.asarray(theta, dtype=float).reshape(-1).copy()
    terms = (theta.size - start) // 2
    if terms > 1:
        pairs = theta[start:].reshape(terms, 2)
        theta[start:] = pairs[np.argsort(pairs[:, 1])].reshape(-1)
    return theta


def spectrum_bounds(terms: int) -> tuple:
    """Lower and upper bounds of the spectrum's coordinates (log10 g, log10 tau)."""
    lo = [math.log10(G_BOUNDS[0]), math.log10(TAU_BOUNDS_S[0])] * terms
    hi = [math.log10(G_BOUNDS[1]), math.log10(TAU_BOUNDS_S[1])] * terms
    return np.array(lo, dtype=float), np.array(hi, dtype=float)
