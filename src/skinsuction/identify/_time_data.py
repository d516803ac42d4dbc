"""The time curves as fitted: the suction cleaned, the sd of every point, its phase.

:func:`fit_data_of` turns a loaded :class:`skinsuction.measured.TimeCurve` into a
:class:`TimeFitData` (the likelihood's sd per point, ``docs/time_identification.md``),
and :func:`search_samples` picks the samples a window focusing reads
(:func:`skinsuction.identify._time_fit.fit_time_model`).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ._time_model import clean_pressure, pressure_breaks

__all__ = ["MODEL_ERROR", "MODEL_ERROR_LAYERS", "STRAIN_SLOPE", "RELEASE_S",
           "TIME_SEARCH_STRIDE", "TimeFitData", "fit_data_of", "time_fit_data",
           "search_samples"]


#: The fast path's model error as an sd, fraction of the curve's largest deflection,
#: per phase: "on" (suction on), "release" (the first 0.1 s after a step's release),
#: "off" (the rest of its off time), "ramp" (every phase of a ramp cycle, mode 2),
#: "rest" (before the first suction: no load, no error).  Between the median draw's
#: RMS and the worst draw's largest error of the fast-path benchmark
#: (docs/viscoelasticity.md: on 0.02-0.03 % / 0.34 %; release 0.68 % / 2.27 %;
#: off 0.22 % / 1.34 %; mode 2 0.03 % / 0.16 %).
MODEL_ERROR = {"on": 0.001, "release": 0.01, "off": 0.004, "ramp": 0.001, "rest": 0.0}

#: Growth of the fast path's model error with the strain of the curve, ``s = U / (a/2)``
#: (the largest deflection over the aperture's radius): its error is the departure from
#: linear theory, so it grows with the strain (docs/effects.md: release errors of
#: 0.2-0.5 % of Uf at s < 0.1, 1-4 % at s = 0.15-0.35, on 2-8 mm probes).  The sd of a
#: phase is ``max(MODEL_ERROR[phase], STRAIN_SLOPE[phase] * s)``: about 0.45 times the
#: worst error measured at that strain.
STRAIN_SLOPE = {"on": 0.01, "release": 0.054, "off": 0.03, "ramp": 0.005, "rest": 0.0}

#: The model error of the per-layer fast path (:class:`TimeCurveModel` with
#: ``layers=True``), fraction of the curve's largest deflection in every loaded phase:
#: its measured error against FE time solves with a spectrum per layer is 0.4-2.8 %
#: of Uf (docs/effects.md, "Which layer creeps").
MODEL_ERROR_LAYERS = {"on": 0.02, "release": 0.02, "off": 0.02, "ramp": 0.02, "rest": 0.0}

#: Seconds after a step's release counted as "release" (where Ur is read).
RELEASE_S = 0.1

#: The window focusing of the time fits reads every ``stride``-th sample, and every
#: sample a geometric ladder of offsets after each change of the suction's slope (the
#: creep transients, 1 ms to 10 s, alike in log time): a fifth of a mode-1 curve's
#: samples. The polish then runs on them all (:func:`search_samples`).
TIME_SEARCH_STRIDE = 8


@dataclass(frozen=True)
class TimeFitData:
    """One time curve as fitted: the cleaned suction, the deflections, the sd of each
    point and its phase (``rest``, ``on``, ``release``, ``off``, ``ramp``)."""

    label: str
    probe_mm: float
    time_s: np.ndarray
    pressure_mbar: np.ndarray
    deflection_mm: np.ndarray
    sd_mm: np.ndarray
    phase: np.ndarray
    noise_sd_mm: float
    scale_mm: float
    used: np.ndarray  # bool: the point is in the likelihood
    breaks: np.ndarray = field(default=None)
    notes: tuple = ()
    model_error: dict = field(default=None)  # the fractions per phase (MODEL_ERROR if None)
    resolution_mm: float = 0.0  # the deflection's rounding step (0: none)

    @property
    def n(self) -> int:
        return int(self.used.sum())


def _phases(curve) -> np.ndarray:
    t = np.asarray(curve.time_s, dtype=float)
    out = np.full(t.size, "rest", dtype=object)
    for c in curve.cycles:
        stop = c.end + 1
        if c.kind == "ramp":
            out[c.onset:stop] = "ramp"
            continue
        out[c.onset:c.release] = "on"
        rel_end = c.release + int(np.searchsorted(t[c.release:stop], t[c.release] + RELEASE_S,
                                                  side="right"))
        out[c.release:rel_end] = "release"
        out[rel_end:stop] = "off"
    return out


def fit_data_of(curve, *, noise_sd_mm: float | None = None, model_error: dict | None = None,
                phases: str = "all") -> TimeFitData:
    """The :class:`TimeFitData` of a loaded :class:`skinsuction.measured.TimeCurve`.

    Parameters
    ----------
    curve : TimeCurve
    noise_sd_mm : float, optional
        Overrides the loader's noise estimate.
    model_error : dict, optional
        Fractions per phase; default :data:`MODEL_ERROR`, raised with the curve's strain
        (:data:`STRAIN_SLOPE`).
    phases : {"all", "on"}
        ``"on"``: only the points while the suction is on (and before it) are fitted.

    Returns
    -------
    TimeFitData
    """
    if phases not in ("all", "on"):
        raise ValueError(f"phases must be 'all' or 'on', not {phases!r}")
    p, note = clean_pressure(curve)
    d = np.asarray(curve.deflection_mm, dtype=float)
    phase = _phases(curve)
    sigma = float(curve.noise_sd_mm if noise_sd_mm is None else noise_sd_mm)
    if not sigma > 0:
        raise ValueError(f"{curve.label}: the noise sd must be positive (the curve shows "
                         "none: give it, --noise-um)")
    used = None if phases == "all" else np.isin(phase, ["rest", "on", "ramp"])
    return time_fit_data(curve.label, curve.probe_mm, curve.time_s, p, d, phase, sigma,
                         model_error=model_error, used=used, notes=(note,),
                         resolution_mm=float(getattr(curve, "resolution_mm", None)
                                             or _grid_step(d)))


def time_fit_data(label, probe_mm, time_s, pressure_mbar, deflection_mm, phase, noise_sd_mm,
                  *, model_error=None, used=None, notes=(), resolution_mm=0.0) -> TimeFitData:
    """A :class:`TimeFitData` from its arrays: each point's sd is the noise, the fast
    path's error in its phase and the space's accuracy (what :func:`fit_data_of` does
    for a loaded curve; a design's noise-free curves use it too).

    Parameters
    ----------
    phase : array of str
        ``rest``, ``on``, ``release``, ``off`` or ``ramp`` per point.
    noise_sd_mm : float
        The noise sd of one deflection (mm), > 0.
    model_error : dict, optional
        Fractions per phase; default :data:`MODEL_ERROR`, raised with the curve's strain
        (:data:`STRAIN_SLOPE`).
    used : array of bool, optional
        The points in the likelihood (default all).
    """
    d = np.asarray(deflection_mm, dtype=float)
    phase = np.asarray(phase, dtype=object)
    sigma = float(noise_sd_mm)
    scale = float(np.percentile(np.abs(d), 99.5))
    if model_error is None:
        # the fast path's error grows with the strain (STRAIN_SLOPE)
        strain = scale / (0.5 * float(probe_mm))
        fractions = {k: max(v, STRAIN_SLOPE.get(k, 0.0) * strain)
                     for k, v in MODEL_ERROR.items()}
    else:
        fractions = {**MODEL_ERROR, **model_error}
    f = np.array([fractions[k] for k in phase], dtype=float)
    # the space's own accuracy target (0.2 % of M and 0.3 µm), as for pressure ramps
    from .measured_fit import MODEL_ERROR_MM, MODEL_ERROR_RELATIVE

    sd = np.sqrt(sigma ** 2 + (f * scale) ** 2 + (MODEL_ERROR_RELATIVE * d) ** 2
                 + MODEL_ERROR_MM ** 2 * (phase != "rest"))
    used = np.ones(d.size, bool) if used is None else np.asarray(used, bool)
    t = np.asarray(time_s, dtype=float)
    p = np.asarray(pressure_mbar, dtype=float)
    return TimeFitData(label, float(probe_mm), t, p, d, sd, phase, sigma, scale, used,
                       pressure_breaks(t, p), tuple(notes), fractions, float(resolution_mm))


def search_samples(d: TimeFitData, stride: int = TIME_SEARCH_STRIDE) -> TimeFitData:
    """The curve ``d`` at the samples the window focusing reads.

    Every ``stride``-th sample, every break of the suction's slope, and after each
    break the samples at offsets 1, 2, 3, 4, 5, 8, 11, 15, ... (each about 1.4 times
    the last): the fast transients stay dense, the slow ones and the elastic curve are
    read every ``stride`` samples. The suction is linear between its breaks, so the
    model at the kept samples is exactly the model of the whole curve there
    (:func:`effective_pressures`); only the sum of squares has fewer terms.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(101) * 0.01
    >>> p = np.where(t >= 0.2, 100.0, 0.0); p[20] = 50.0     # a step at 0.2 s
    >>> d = time_fit_data("x", 2.0, t, p, 0.1 * p / 100, np.full(101, "on"), 0.003)
    >>> s = search_samples(d, stride=10)
    >>> s.time_s.size, [round(float(v), 2) for v in s.time_s[:12]]
    (32, [0.0, 0.01, 0.02, 0.03, 0.04, 0.05, 0.08, 0.1, 0.11, 0.15, 0.19, 0.2])
    >>> bool(np.all(np.isin(d.time_s[d.breaks], s.time_s)))
    True
    """
    size = d.time_s.size
    if stride <= 1 or size <= 2 * stride:
        return d
    breaks = d.breaks if d.breaks is not None else pressure_breaks(d.time_s, d.pressure_mbar)
    ladder = np.unique(np.round(1.4 ** np.arange(int(np.log(size) / np.log(1.4)) + 2)))
    keep = np.zeros(size, bool)
    keep[::stride] = True
    keep[[0, size - 1]] = True
    ends = np.append(breaks[1:], size - 1)
    for a, b in zip(breaks, ends):
        offsets = ladder[ladder < min(b - a, 8 * stride)].astype(int)
        keep[a] = True
        keep[a + offsets] = True
    idx = np.flatnonzero(keep)
    return replace(d, time_s=d.time_s[idx], pressure_mbar=d.pressure_mbar[idx],
                   deflection_mm=d.deflection_mm[idx], sd_mm=d.sd_mm[idx],
                   phase=d.phase[idx], used=d.used[idx],
                   breaks=np.searchsorted(idx, breaks).astype(int))


def _grid_step(d) -> float:
    """The grid the deflections lie on, 0 if none: the loader's rule without its
    20-step range (that misses a small curve, 0.08 mm at 0.01 mm under a 2 mm probe)."""
    from skinsuction.measured import grid_step

    return grid_step(d, min_steps=2) or 0.0
