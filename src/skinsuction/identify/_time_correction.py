"""The FE correction of a time fit: the fast path's error, measured at the fit and removed.

The fast path (:class:`~skinsuction.identify.TimeCurveModel`) drives the skin's
elastic curve by the effective suction.  That is exact in the linear limit; with a
strong creep at large strain it is not: under the 8 mm probe, g = 0.73 and a
stiffening dermis, it misses the FE time solve by 42 µm (2 % of the curve), enough
to prefer a wrong elastic effect by 400 in chi^2 (docs/effects.md).

At a fit theta the FE time solver gives the model's own curve F(theta); its
difference from the fast path there, delta = F(theta) - f(theta), is the fast
path's error at that skin.  The fast path is then fitted again to the data less
delta (delta held), from theta: one step of a defect correction, whose fixed point
is the FE model's least-squares fit where delta varies slowly with theta.  Two
steps change chi^2 by about 1 on the curves measured.  The FE solves use the mesh of
the space's rays, so that delta is the fast path's error alone: on a coarser mesh
(refinement 0.5) it also carried that mesh's discretisation error, which moved X1h
by 0.6 % under the 6 mm probe (three times its interval's half-width) for about the
same CPU.
"""

from __future__ import annotations

import dataclasses
import time
from typing import NamedTuple

import numpy as np

__all__ = ["time_fit_skin", "fe_time_curve", "fe_corrected_fit", "FittedTimeModel"]

#: Steps after each switch of the suction (s): 1 ms doubling, as the virtual experiments.
GRADED_STEPS_S = 1e-3 * 2.0 ** np.arange(6)

#: The graded steps of :func:`fe_time_curve`: 2 ms after each break of the suction's
#: slope, doubling to at most 0.2 s.  Between breaks the suction is linear, so the load
#: path is the samples' own; a mode-1 curve of 10.5 s at 100 Hz takes 96 steps instead
#: of about 1 100, and differs from the solve at every sample by at most 0.22 µm, a
#: fourteenth of a Cutometer's 3 µm quantisation noise (benchmarks/time_correction_steps.py;
#: growing by 1.5 to 0.15 s until 7 December 2026: 145 steps, 0.12 µm, a third more
#: Newton iterations).
FIRST_STEP_S, STEP_GROWTH, MAX_STEP_S = 2e-3, 2.0, 0.2


class FittedTimeModel(NamedTuple):
    """A time fit with what it was fitted to, for a later fit of the same curves to reuse.

    ``fit`` (TimeFit), ``data`` (the curves less the fast path's error, as
    :func:`fe_corrected_fit` returns them, or the curves), ``correction`` (its record),
    ``fitted_to`` (the measured curves, TimeFitData), ``geometry`` (the layers the
    rays were read at) and ``effect`` (the elastic cause fitted with the spectrum, or
    None).
    """

    fit: object
    data: list
    correction: dict
    fitted_to: tuple
    geometry: object = None
    effect: str | None = None

    def fits(self, data, terms: int, steps: int, effect=None, geometry=None) -> bool:
        """Whether this is the fit of ``terms`` Prony terms and ``effect`` to ``data``
        at ``geometry``, corrected by ``steps`` FE steps (the same curves, points,
        weights and phases).

        Examples
        --------
        >>> from types import SimpleNamespace as NS
        >>> d = NS(label="2 mm", time_s=np.arange(3.0), deflection_mm=np.ones(3),
        ...        sd_mm=np.ones(3), used=np.ones(3, bool))
        >>> m = FittedTimeModel(NS(terms=1), [d], {"applied": True, "iterations": 2}, (d,))
        >>> m.fits([d], 1, 2), m.fits([d], 2, 2), m.fits([d], 1, 0)
        (True, False, False)
        """
        record = self.correction or {}
        done = int(record.get("iterations", 0)) if record.get("applied") else 0
        if (self.fit.terms != terms or self.effect != effect or done != int(steps)
                or self.geometry != geometry or len(data) != len(self.fitted_to)):
            return False
        keys = ("time_s", "deflection_mm", "sd_mm", "used")
        return all(a.label == b.label and all(np.array_equal(getattr(a, k), getattr(b, k))
                                              for k in keys)
                   for a, b in zip(data, self.fitted_to))


def solve_times(time_s, breaks, grading=None) -> np.ndarray:
    """The FE solve's times: every break of the suction's slope, and graded steps after each.

    Parameters
    ----------
    time_s : array_like
        The samples (s, increasing).
    breaks : array_like of int
        Sample indices where the suction's slope changes, with the first and the last.
    grading : tuple of float, optional
        ``(first step s, growth, largest step s)``; default
        ``(FIRST_STEP_S, STEP_GROWTH, MAX_STEP_S)``.

    Returns
    -------
    numpy.ndarray

    Examples
    --------
    One second of constant suction: 12 steps instead of a sample's each, the
    largest 0.2 s:

    >>> t = solve_times([0.0, 0.5, 1.0], [0, 2])
    >>> t.size, t[:4].round(5).tolist(), float(np.diff(t).max().round(3))
    (12, [0.0, 0.002, 0.006, 0.014], 0.2)
    """
    first, growth, largest = grading or (FIRST_STEP_S, STEP_GROWTH, MAX_STEP_S)
    t = np.asarray(time_s, dtype=float)
    edges = t[np.unique(np.concatenate([[0], np.asarray(breaks, int), [t.size - 1]]))]
    out = [edges]
    for a, b in zip(edges[:-1], edges[1:]):
        x, step = a + first, first
        while x < b - 1e-9:
            out.append([x])
            step = min(step * growth, largest)
            x += step
    return np.unique(np.round(np.concatenate(out), 9))


def at_samples(time_s, breaks, solved_s, solved_mm) -> np.ndarray:
    """A solve at :func:`solve_times` read at the samples: PCHIP between breaks (the
    deflection's slope jumps at each)."""
    from scipy.interpolate import PchipInterpolator

    t = np.asarray(time_s, dtype=float)
    edges = t[np.unique(np.concatenate([[0], np.asarray(breaks, int), [t.size - 1]]))]
    out = np.interp(t, solved_s, solved_mm)
    for a, b in zip(edges[:-1], edges[1:]):
        node = (solved_s >= a - 1e-9) & (solved_s <= b + 1e-9)
        if node.sum() > 2:
            sel = (t >= a - 1e-9) & (t <= b + 1e-9)
            out[sel] = PchipInterpolator(solved_s[node], solved_mm[node])(t[sel])
    return out


def time_fit_skin(parameters: dict, geometry, bottom: str, cause=None):
    """The :class:`~skinsuction.model.Skin` of a time fit's parameters.

    Long-time moduli; the spectrum on both layers (``g``, ``tau_s``), or one per layer
    (``g_dermis`` ...); the elastic cause's parameter, if any, where it acts.

    Parameters
    ----------
    parameters : dict
        :meth:`TimeCurveModel.parameters`.
    geometry : skinsuction.space.Geometry
        The layers (``t_d``, ``t_h``).
    bottom : str
    cause : skinsuction.space.Cause, optional

    Returns
    -------
    Skin

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> skin = time_fit_skin({"X1d": 0.1, "X1h": 0.002, "g_dermis": [0.5],
    ...                       "tau_s_dermis": [0.3], "g_hypodermis": [1.0],
    ...                       "tau_s_hypodermis": [0.5]},
    ...                      SimpleNamespace(t_d=1.0, t_h=2.0), "fixed")
    >>> [layer.spectrum.g for layer in skin.layers], skin.layers[1].thickness
    ([(0.5,), (1.0,)], 2.0)
    """
    from skinsuction.model import Prony, Skin

    spectrum = (Prony(parameters["g"], parameters["tau_s"]) if parameters.get("g")
                else Prony())
    if parameters.get("g_dermis"):
        spectrum = {layer: Prony(parameters[f"g_{layer}"], parameters[f"tau_s_{layer}"])
                    for layer in ("dermis", "hypodermis")}
    skin = Skin.two_layer(parameters["X1d"], parameters["X1h"], t_d=geometry.t_d,
                          t_h=geometry.t_h, bottom=bottom, spectrum=spectrum)
    if cause is not None:
        skin = skin.replace({path: parameters[cause.symbol] for path in cause.paths})
    return skin


def fe_time_curve(skin, data, mesh=None, steps: str = "graded", grading=None) -> np.ndarray:
    """The FE time solve of ``skin`` under one fitted curve's suction, at its samples.

    Parameters
    ----------
    skin : skinsuction.model.Skin
    data : TimeFitData
        The curve (its cleaned suction, times, probe and breaks).
    mesh : dict, optional
        Mesh settings (default: the model's reference mesh).
    steps : {"graded", "samples"}
        "graded": the steps of :func:`solve_times`, read at the samples by PCHIP
        between breaks; "samples": a step at every sample and, after each break,
        at :data:`GRADED_STEPS_S` (as the virtual experiments; the reference).
    grading : tuple of float, optional
        The graded steps' ``(first s, growth, largest s)`` (:func:`solve_times`).

    Returns
    -------
    numpy.ndarray
        The apex deflection (mm) at ``data.time_s``.

    Raises
    ------
    RuntimeError
        If the FE time solve stops.
    """
    from skinsuction.viscoelastic import simulate_history

    t = np.asarray(data.time_s, dtype=float)
    p = np.asarray(data.pressure_mbar, dtype=float)
    if steps == "graded":
        tf = solve_times(t, data.breaks, grading)
    elif steps == "samples":
        switches = t[np.asarray(data.breaks, dtype=int)]
        fine = (switches[:, None] + GRADED_STEPS_S[None, :]).ravel()
        tf = np.unique(np.round(np.concatenate([t, fine[fine < t[-1]]]), 9))
    else:
        raise ValueError(f"steps must be 'graded' or 'samples', not {steps!r}")
    h = simulate_history(skin, tf, np.interp(tf, t, p), probe=data.probe_mm,
                         mesh=mesh)
    if not h.converged:
        raise RuntimeError(f"{data.label}: the FE time solve stopped: {h.reason}")
    m = np.asarray(h.deflection_mm, dtype=float)
    return at_samples(t, data.breaks, tf, m) if steps == "graded" else np.interp(t, tf, m)


def fe_corrected_fit(rays: dict, data: list, fit, skin_of, *, mesh=None, iterations: int = 2,
                     seed=0, layers: bool = False) -> tuple:
    """A time fit corrected for the fast path's error by FE time solves at the fit.

    Parameters
    ----------
    rays : dict
        Probe (mm) -> RaySpace, as :func:`fit_time_model`.
    data : list of TimeFitData
        The measured curves.
    fit : TimeFit
        The fast path's fit, the start.
    skin_of : callable
        ``skin_of(parameters) -> Skin``: the skin of a fit's parameters.
    mesh : dict, optional
        Mesh of the FE solves (default: the rays' own, ``spec.mesh``).
    iterations : int
        Correction steps (each: one FE solve per curve and a polish).
    seed : int or SeedSequence
    layers : bool
        A spectrum per layer (as :func:`fit_time_model`).

    Returns
    -------
    fit : TimeFit
        The corrected fit: its chi^2 and residuals are those of the data less the
        last delta, its ``fitted_mm`` the fast path plus delta (the FE model's curve).
    corrected : list of TimeFitData
        The data less the last delta (for intervals: delta held).
    record : dict
        ``applied``, ``mesh``, ``iterations``, ``chi2`` (the fast fit's, then after
        each step), ``fe_chi2_at_fast_fit`` (the FE curve of the fast path's
        estimate against the data), ``delta_max_um`` per curve, ``cpu_s``.

    Raises
    ------
    RuntimeError
        If an FE time solve stops (the caller keeps the fast fit and says so).
    """
    from ._time_fit import TimeCurveModel, fit_time_model

    t0 = time.process_time()
    if mesh is None:
        mesh = dict(next(iter(rays.values())).spec.mesh)
    theta, chi2, corrected, fe_chi2 = np.asarray(fit.theta, float), [float(fit.chi2)], data, None
    fast_model = TimeCurveModel(rays, data, fit.terms, layers)
    for _ in range(int(iterations)):
        fast = [m[0] for m in fast_model(theta[None, :])]
        skin = skin_of(fast_model.parameters(theta))
        fe = [fe_time_curve(skin, d, mesh) for d in data]
        delta = [F - f for F, f in zip(fe, fast)]
        if fe_chi2 is None:
            fe_chi2 = float(sum(np.sum(((d.deflection_mm - F) / d.sd_mm)[d.used] ** 2)
                                for d, F in zip(data, fe)))
        corrected = [dataclasses.replace(d, deflection_mm=d.deflection_mm - dl)
                     for d, dl in zip(data, delta)]
        fit = fit_time_model(rays, corrected, terms=fit.terms, seed=seed, repeats=0,
                             starts=[theta], layers=layers)
        theta = np.asarray(fit.theta, float)
        chi2.append(float(fit.chi2))
    fitted = [f + dl for f, dl in zip(fit.fitted_mm, delta)]
    fit = dataclasses.replace(fit, fitted_mm=fitted)
    record = {"applied": True, "mesh": dict(mesh),
              "iterations": int(iterations), "chi2": chi2, "fe_chi2_at_fast_fit": fe_chi2,
              "delta_max_um": {d.label: float(1e3 * np.max(np.abs(dl)))
                               for d, dl in zip(data, delta)},
              "cpu_s": float(time.process_time() - t0)}
    return fit, corrected, record
