"""Cutometer pressure histories with time grids for the implicit solver.

Mode 1: constant suction switched on and off (e.g. 400 mbar, 3 s on / 2 s off);
mode 2: a linear ramp up and down at a constant rate. The suction is piecewise
linear between the returned points; each on/off switch is a short linear ramp
(``rise_s``; the device's own is not documented, an assumption). The time steps
start small after each switch (``first_step_s``) and grow geometrically to
``max_step_s``: the response changes fastest right after a switch, at the
shortest relaxation time.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..model import ParameterError

#: Ue is read 0.1 s after the suction starts (the Cutometer's convention): the
#: phases "rise" and "release" are the first 0.1 s after each switch
READING_S = 0.1


@dataclass(frozen=True)
class PressureHistory:
    """Times (s), suction (mbar) and the phase of each point: ``"rise"`` (the
    first 0.1 s from suction on, or the loading ramp in mode 2), ``"hold"``,
    ``"release"`` (the first 0.1 s from suction off, or the unloading ramp),
    ``"off"``; the first point (t = 0, at rest) is ``"rest"``."""

    times_s: np.ndarray
    pressure_mbar: np.ndarray
    phase: np.ndarray


def graded_steps(length, first, growth, largest):
    """Interior points of ``[0, length]`` with steps from ``first`` growing by
    ``growth`` up to ``largest``, the last step stretched or shrunk to fit.

    Parameters
    ----------
    length, first, largest : float
        The span, the first step and the largest step (s).
    growth : float
        Factor from one step to the next (>= 1).

    Returns
    -------
    ndarray
        The points after 0, ``length`` last.

    Examples
    --------
    >>> graded_steps(1.0, 0.1, 2.0, 0.4).round(6).tolist()
    [0.1, 0.3, 0.7, 1.0]
    """
    points, t, h = [], 0.0, first
    while t + h < length - 0.5 * min(h, largest):
        t += h
        points.append(t)
        h = min(h * growth, largest)
    points.append(length)
    return np.array(points)


def mode1_history(pressure_mbar=400.0, on_s=3.0, off_s=2.0, cycles=2, rise_s=0.01,
                  first_step_s=1e-3, growth=1.25, max_step_s=0.05):
    """Mode 1: ``cycles`` of suction ``pressure_mbar`` held ``on_s``, released for
    ``off_s``; each switch a linear ramp of ``rise_s``.

    Parameters
    ----------
    pressure_mbar : float
        The suction of the hold (mbar).
    on_s, off_s : float
        Suction on and off per cycle (s), each longer than ``rise_s``.
    cycles : int
        How many times.
    rise_s : float
        Length of each switch's linear ramp (s).
    first_step_s, growth, max_step_s : float
        The time steps after each switch: the first, its growth, the largest.

    Returns
    -------
    PressureHistory

    Examples
    --------
    >>> h = mode1_history(400, on_s=0.5, off_s=0.5, cycles=1, max_step_s=0.1)
    >>> float(h.pressure_mbar.max()), float(h.times_s[-1]), sorted(map(str, set(h.phase)))
    (400.0, 1.0, ['hold', 'off', 'release', 'rest', 'rise'])
    """
    if not (pressure_mbar > 0 and on_s > rise_s > 0 and off_s > rise_s and cycles >= 1):
        raise ParameterError("mode 1: need pressure > 0, on_s and off_s > rise_s > 0, cycles >= 1")
    times, pressures, phases = [0.0], [0.0], ["rest"]

    def phase(start, length, p_from, p_to, first_name, later_name):
        ramp = graded_steps(rise_s, min(first_step_s, rise_s), 1.0, first_step_s)
        rest = rise_s + graded_steps(length - rise_s, first_step_s, growth, max_step_s)
        for s in np.concatenate([ramp, rest]):
            times.append(start + s)
            pressures.append(p_from + (p_to - p_from) * min(s / rise_s, 1.0))
            phases.append(first_name if s <= READING_S + 1e-12 else later_name)

    start = 0.0
    for _ in range(cycles):
        phase(start, on_s, 0.0, pressure_mbar, "rise", "hold")
        phase(start + on_s, off_s, pressure_mbar, 0.0, "release", "off")
        start += on_s + off_s
    return PressureHistory(np.array(times), np.array(pressures), np.array(phases))


def mode2_history(peak_mbar=500.0, rate_mbar_s=25.0, step_s=0.25, hold_s=0.0,
                  first_step_s=1e-3, growth=1.25, fall_rate_mbar_s=None, cycles=1):
    """Mode 2: a ramp from 0 to ``peak_mbar`` at ``rate_mbar_s``, an optional hold,
    and a ramp back to 0 at ``fall_rate_mbar_s`` (default: the same rate), repeated
    ``cycles`` times back to back (ISRN Dermatology 2013: 25 mbar/s for 20 s). Steps
    of ``step_s``, graded from ``first_step_s`` after each kink.

    Parameters
    ----------
    peak_mbar : float
        The largest suction (mbar).
    rate_mbar_s : float
        Loading rate (mbar/s).
    step_s : float
        Largest time step (s).
    hold_s : float
        Hold at the peak (s; 0: none).
    first_step_s, growth : float
        The first time step after each kink and its growth.
    fall_rate_mbar_s : float, optional
        Unloading rate (mbar/s; default ``rate_mbar_s``).
    cycles : int
        How many ramps up and down, back to back.

    Returns
    -------
    PressureHistory

    Examples
    --------
    >>> h = mode2_history(100, 50, step_s=0.5)
    >>> float(h.times_s[-1]), float(h.pressure_mbar.max()), sorted(map(str, set(h.phase)))
    (4.0, 100.0, ['release', 'rest', 'rise'])
    >>> h = mode2_history(100, 50, step_s=0.5, fall_rate_mbar_s=25, cycles=2)
    >>> float(h.times_s[-1]), int((h.pressure_mbar == 100).sum())
    (12.0, 2)
    """
    fall_rate = rate_mbar_s if fall_rate_mbar_s is None else fall_rate_mbar_s
    if not (peak_mbar > 0 and rate_mbar_s > 0 and fall_rate > 0 and step_s > 0
            and hold_s >= 0 and int(cycles) == cycles >= 1):
        raise ParameterError("mode 2: need peak, rates and step > 0, hold >= 0, cycles >= 1")
    times, pressures, phases = [0.0], [0.0], ["rest"]
    segments = [(peak_mbar / rate_mbar_s, 0.0, peak_mbar, "rise")]
    if hold_s > 0:
        segments.append((hold_s, peak_mbar, peak_mbar, "hold"))
    segments.append((peak_mbar / fall_rate, peak_mbar, 0.0, "release"))
    start = 0.0
    for length, p_from, p_to, name in segments * int(cycles):
        for s in graded_steps(length, min(first_step_s, step_s), growth, step_s):
            times.append(start + s)
            pressures.append(p_from + (p_to - p_from) * s / length)
            phases.append(name)
        start += length
    return PressureHistory(np.array(times), np.array(pressures), np.array(phases))
