"""The phases of a time curve, its protocol, the deflection's resolution and noise.

What :func:`skinsuction.measured.load_time_curves` finds in a checked curve
(:mod:`._timecurve` reads and checks the file, :mod:`._timecheck` holds the
plausibility checks of its samples).

Phases
------
The suction is found from the pressure alone, robust to its noise: the pressure is
median-filtered (5 samples: a spike of one or two samples goes), its noise sd is
taken from its second differences (a ramp has none), and a switch with hysteresis
turns *on* above ``max(0.3 P, min(6 sd, 0.6 P))`` (``P`` the largest filtered
pressure) and *off* at or below ``max(0.02 P, min(3 sd, 0.1 P), 1 mbar)``.  Each *on*
stretch is a cycle:

* ``rise``: from the suction onset (the first sample after the pressure last sat at
  the off level) to the first sample within ``max(0.03 x peak, 4 sd)`` of the
  cycle's peak;
* ``hold``: from there to the last sample within that band;
* ``release``: from the next sample (the release onset) until the pressure is back at
  the off level;
* ``off``: from there to the next onset (or the end of the file).

A cycle is a ``step`` (constant suction) if its rise and its release each take at most
10 % of it and at least 90 % of its hold lies in the band; a ``ramp`` if its rise and
release each take at least 25 % of it and the pressure is linear in time along both
(R^2 >= 0.95); else ``other``.  A ramp leaves the off level late (8 mbar at 25 mbar/s
is 0.3 s), so its onset and its return to the off level are the samples nearest to
where the lines fitted to its rise and its release (10-90 % of the peak) cross 0.  The
protocol of a curve is ``"mode 1"`` (every cycle a step, their levels within 10 %),
``"mode 2"`` (every cycle a ramp) or ``"other"``.

Quantisation and noise
----------------------
A Cutometer reads the deflection to 0.01 mm.  The loader finds the resolution ``q``
(the smallest gap between distinct deflections, if every deflection is a whole
multiple of it) and reports it (``TimeCurve.resolution_mm`` and a note).  The noise
sd comes from unit-norm third differences in time (those of :mod:`skinsuction.noise`)
within each phase, after 0.1 s of settling, and is never below the sd of the rounding,
``q / sqrt(12)`` (2.9 µm at 0.01 mm): a reading is off the true curve by at least
that, so a fit should not be asked to do better.  Steps of ``q`` are quantisation,
not noise and not misfit: no check counts them as a fall or a jump.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["SETTLE_S", "Cycle", "grid_step"]

#: Seconds after a phase starts that the noise estimate skips (the 10 ms creep term
#: has settled to e^-10 of its size).
SETTLE_S = 0.1

# the switch of the suction (fractions of the largest filtered pressure P)
_ON_FRACTION, _OFF_FRACTION, _BAND_FRACTION = 0.3, 0.02, 0.03
# a step rises and releases within this fraction of its cycle; a ramp takes at least
# _RAMP_FRACTION on each side
_STEP_FRACTION, _RAMP_FRACTION, _HOLD_IN_BAND = 0.10, 0.25, 0.90


@dataclass(frozen=True)
class Cycle:
    """One application of the suction, as sample indices into its :class:`TimeCurve`.

    Attributes
    ----------
    index : int
        1-based, in time order.
    kind : str
        ``"step"`` (constant suction), ``"ramp"`` (linear up and down) or ``"other"``.
    onset : int
        First sample of the suction (the pressure has left the off level).
    hold_start, hold_end : int
        First and last sample within the band of the cycle's peak pressure.
    release : int
        The release onset: the first sample after the hold (``hold_end + 1``).
    off : int or None
        First sample back at the off level (None if the file ends before).
    end : int
        Last sample of the cycle: the one before the next onset, or the file's last.
    level_mbar : float
        Median pressure of the hold (of a ramp: its peak, median-filtered).
    """

    index: int
    kind: str
    onset: int
    hold_start: int
    hold_end: int
    release: int
    off: int | None
    end: int
    level_mbar: float



# ------------------------------------------------------------------ phases
def _pressure_noise(p) -> float:
    """Noise sd (mbar) of the pressure from the MAD of its second differences: a ramp
    has none, and a switch spoils only a few of them."""
    if p.size < 5:
        return 0.0
    d2 = np.diff(p, 2)
    return float(1.4826 * np.median(np.abs(d2 - np.median(d2))) / math.sqrt(6.0))


def _find_cycles(t, p, p_sd) -> list:
    from scipy.ndimage import median_filter

    ps = median_filter(p, size=5, mode="nearest")
    big = float(ps.max())
    if big <= 0:
        return []
    # the noise sets the switch, but never above half the suction: with holds of a few
    # samples every second difference is a switch and the noise sd comes out large
    on_level = max(_ON_FRACTION * big, min(6.0 * p_sd, 0.6 * big))
    off_level = max(_OFF_FRACTION * big, min(3.0 * p_sd, 0.1 * big), 1.0)
    if big <= on_level or big <= off_level:
        return []
    spans, state, start = [], False, 0
    for k in range(ps.size):
        if not state and ps[k] > on_level:
            j = k
            while j > 0 and ps[j - 1] > off_level:
                j -= 1
            state, start = True, j
        elif state and ps[k] <= off_level:
            spans.append((start, k))
            state = False
    if state:
        spans.append((start, None))
    found = []
    for a, off in spans:
        e = off if off is not None else ps.size
        seg = ps[a:e]
        peak = float(seg.max())
        band = max(_BAND_FRACTION * peak, 4.0 * p_sd)
        inband = np.flatnonzero(seg >= peak - band)
        hs, he = a + int(inband[0]), a + int(inband[-1])
        kind = _kind(t, ps, a, hs, he, e, inband.size)
        if kind == "ramp":
            # a ramp leaves the off level late (8 mbar at 25 mbar/s is 0.3 s): its
            # onset and its return are where its lines cross 0
            a, off = _ramp_ends(t, ps, a, hs, he, e, off, found[-1][4] if found else 0)
            level = peak
        else:
            level = float(np.median(p[hs:he + 1]))
        found.append([kind, a, hs, he, off if off is not None else None, level])
    cycles = []
    for i, (kind, a, hs, he, off, level) in enumerate(found):
        end = found[i + 1][1] - 1 if i + 1 < len(found) else ps.size - 1
        cycles.append(Cycle(i + 1, kind, a, hs, he, he + 1, off, end, level))
    return cycles


def _ramp_ends(t, ps, a, hs, he, e, off, previous_off):
    """Onset and return of a ramp: the samples nearest to where its rising and falling
    lines (fitted between 10 % and 90 % of the peak) cross 0."""
    from scipy.stats import linregress

    peak = ps[hs:he + 1].max()
    up = np.arange(a, hs + 1)
    up = up[(ps[up] >= 0.1 * peak) & (ps[up] <= 0.9 * peak)]
    if up.size >= 3:
        fit = linregress(t[up], ps[up])
        if fit.slope > 0:
            k = int(np.argmin(np.abs(t - (-fit.intercept / fit.slope))))
            a = min(a, max(k, previous_off or 0))
    if off is not None:
        down = np.arange(he, e)
        down = down[(ps[down] >= 0.1 * peak) & (ps[down] <= 0.9 * peak)]
        if down.size >= 3:
            fit = linregress(t[down], ps[down])
            if fit.slope < 0:
                k = int(np.argmin(np.abs(t - (-fit.intercept / fit.slope))))
                off = min(max(off, k), ps.size - 1)
    return a, off


def _kind(t, ps, a, hs, he, e, n_band) -> str:
    total = t[e - 1] - t[a] if e - 1 > a else 0.0
    if total <= 0:
        return "other"
    rise, fall = t[hs] - t[a], t[e - 1] - t[he]
    if rise <= _STEP_FRACTION * total and fall <= _STEP_FRACTION * total \
            and n_band >= _HOLD_IN_BAND * (he - hs + 1):
        return "step"
    if rise >= _RAMP_FRACTION * total and fall >= _RAMP_FRACTION * total \
            and _linear(t[a:hs + 1], ps[a:hs + 1]) and _linear(t[he:e], ps[he:e]):
        return "ramp"
    return "other"


def _linear(x, y) -> bool:
    if x.size < 3:
        return False
    from scipy.stats import linregress

    return linregress(x, y).rvalue ** 2 >= 0.95


def _protocol(cycles) -> str:
    kinds = {c.kind for c in cycles}
    if kinds == {"step"}:
        levels = np.array([c.level_mbar for c in cycles])
        if np.all(np.abs(levels - np.median(levels)) <= 0.1 * np.median(levels)):
            return "mode 1"
    if kinds == {"ramp"}:
        return "mode 2"
    return "other"


def _protocol_note(protocol, cycles, t) -> str:
    def span(a, b):
        return float(t[b] - t[a]) if b is not None and b > a else 0.0

    if protocol == "mode 1":
        on = np.median([span(c.onset, c.release) for c in cycles])
        offs = [span(c.release, c.end + 1) for c in cycles[:-1]]
        level = np.median([c.level_mbar for c in cycles])
        return (f"mode 1: {len(cycles)} cycles at {level:.4g} mbar, {on:.3g} s on"
                + (f" / {np.median(offs):.3g} s off" if offs else ""))
    if protocol == "mode 2":
        return (f"mode 2: {len(cycles)} ramp(s) up to {max(c.level_mbar for c in cycles):.4g}"
                " mbar")
    return ("other protocol: cycles " + ", ".join(f"{c.index} {c.kind}" for c in cycles)
            + " (R0-R9 need mode 1)")


# ------------------------------------------------------------------ resolution, noise
def grid_step(d, min_steps: int = 20) -> float | None:
    """The deflection's grid step (its resolution), if it is read to one.

    The smallest gap between distinct values, if every value is a whole multiple of
    it (to 2 % of a step) and the range spans at least ``min_steps`` steps.

    Parameters
    ----------
    d : array_like
        Deflections (mm).
    min_steps : int
        Fewest steps the range must span: 20 to read a resolution off a file (two
        levels 0.5 mm apart are a square wave, not a resolution), fewer for a
        curve known to be quantised.

    Returns
    -------
    float or None
        The step (mm, to 3 significant digits), or None if the values are not on a
        grid, span too few steps, or the step is below 1e-6 mm.

    Examples
    --------
    >>> grid_step([0.0, 0.01, 0.03, 0.2, 0.31])
    0.01
    >>> grid_step([0.0, 0.012, 0.031], min_steps=2) is None
    True
    """
    d = np.asarray(d, dtype=float)
    values = np.unique(d)
    if values.size < 2:
        return None
    q = float(np.diff(values).min())
    if q < 1e-6 or q > np.ptp(values) / min_steps:
        return None
    r = d / q
    if np.max(np.abs(r - np.round(r))) > 0.02:
        return None
    return float(f"{q:.3g}")  # 0.01 read back from text is 0.01, not 0.0099999


def _noise_sd(t, d, cycles) -> float:
    """Noise sd (mm) from third differences within the phases, after SETTLE_S of each
    (a phase change is a kink, not noise): the estimator of :mod:`skinsuction.noise`,
    in time instead of pressure."""
    cuts = {0, d.size}
    for c in cycles:
        cuts |= {c.onset, c.hold_start, c.release} | ({c.off} if c.off is not None else set())
    cuts = sorted(k for k in cuts if 0 <= k <= d.size)
    squares = []
    for a, b in zip(cuts[:-1], cuts[1:]):
        k = a + int(np.searchsorted(t[a:b], t[a] + SETTLE_S))
        if b - k >= 8:
            squares.append(_third_differences(t[k:b], d[k:b]) ** 2)
    if not squares:
        return 0.0
    return float(np.sqrt(np.concatenate(squares).mean()))


def _third_differences(t, d) -> np.ndarray:
    """Unit-norm third differences (they remove a quadratic trend over four samples)."""
    step = np.diff(t)
    if np.ptp(step) <= 0.01 * step.mean():  # even sampling: the binomial weights
        return np.diff(d, 3) / math.sqrt(20.0)
    from skinsuction.noise import difference_weights

    c = difference_weights(t, 3)
    return (c * d[np.arange(len(c))[:, None] + np.arange(4)]).sum(axis=1)
