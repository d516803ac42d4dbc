"""The plausibility checks of a time curve's samples: located errors, warnings.

Each check raises a :class:`MeasuredDataError` naming the file, the line and the
column (the rules are listed under "Errors" in :mod:`._timecurve`); a doubt about
data that may still be real is a warning.
"""

from __future__ import annotations

import numpy as np

from ._checks import APERTURE_FLOOR, APERTURE_LIMIT, BAR_AT_MOST_MBAR, LOW_PRESSURE_MBAR, \
    M_BELOW_MM, PA_ABOVE_MBAR, UM_ABOVE_MM
from ._phases import _pressure_noise
from ._types import MeasuredDataError

__all__ = ["DEVICE_MAX_MBAR"]

#: Largest suction of the device range (mbar): a Cutometer applies at most about
#: 500 mbar; above 1000 a file "looks like Pa".
DEVICE_MAX_MBAR = 600.0

# a rise below this many noise sd (and 2 quanta) is "does not rise"
_RISE_NOISE_SD = 4.0


def _check_time(path, label, lines, t):
    step = np.diff(t)
    bad = np.flatnonzero(step <= 0)
    if bad.size:
        k = int(bad[0]) + 1
        what = "repeats" if step[k - 1] == 0 else "is before"
        hint = "; a new curve? add a 'curve' column with a replicate id" if t[k] <= t[0] else ""
        raise MeasuredDataError(path, int(lines[k]), "time_s", f"time {t[k]:g} s {what} "
                                f"{t[k - 1]:g} s on line {lines[k - 1]}; times must strictly "
                                f"increase within the {label}{hint}")


def _check_pressure(path, label, lines, p) -> list:
    k_max, k_min = int(np.argmax(p)), int(np.argmin(p))
    top = p[k_max]
    if p[k_min] < 0 and -p[k_min] > max(top, 0.0):
        raise MeasuredDataError(path, int(lines[k_min]), "pressure_mbar", f"pressure "
                                f"{p[k_min]:g} mbar is negative; give the suction as positive "
                                "mbar")
    if top > PA_ABOVE_MBAR:
        raise MeasuredDataError(path, int(lines[k_max]), "pressure_mbar", f"largest pressure "
                                f"{top:g} mbar looks like Pa, not mbar (1 mbar = 100 Pa; a "
                                "Cutometer applies at most about 500 mbar)")
    if top > DEVICE_MAX_MBAR:
        raise MeasuredDataError(path, int(lines[k_max]), "pressure_mbar", f"largest pressure "
                                f"{top:g} mbar is above the device range (a Cutometer applies "
                                f"at most about 500 mbar; <= {DEVICE_MAX_MBAR:g} accepted): "
                                "is the unit mbar (1 mbar = 100 Pa = 0.1 kPa)?")
    if top <= 0:
        raise MeasuredDataError(path, int(lines[k_max]), "pressure_mbar",
                                f"the {label} has no pressure above 0")
    if top <= BAR_AT_MOST_MBAR:
        raise MeasuredDataError(path, int(lines[k_max]), "pressure_mbar", f"largest pressure "
                                f"{top:g} mbar looks like bar or kPa, not mbar (100 mbar = "
                                "0.1 bar = 10 kPa)")
    # a sensor's zero wanders by a few mbar: only a negative pressure beyond that is wrong
    floor = max(10.0, 6.0 * _pressure_noise(p), 0.05 * top)
    if p[k_min] < -floor:
        raise MeasuredDataError(path, int(lines[k_min]), "pressure_mbar", f"pressure "
                                f"{p[k_min]:g} mbar is below zero beyond the sensor's noise "
                                f"(-{floor:.3g} mbar); give the suction as positive mbar")
    if top <= LOW_PRESSURE_MBAR:
        return [f"{path}: the {label} reaches only {top:g} mbar (suction protocols apply "
                "50-500 mbar): if the file is in kPa, multiply by 10"]
    return []


def _check_deflection(path, label, probe, lines, d):
    a = np.abs(d)
    k = int(np.argmax(a))
    top, floor = APERTURE_LIMIT * probe, APERTURE_FLOOR * probe
    if a[k] > min(top, UM_ABOVE_MM):
        raise MeasuredDataError(path, int(lines[k]), "deflection_mm", f"largest deflection "
                                f"{d[k]:g} mm looks like µm, not mm (1 mm = 1000 µm; a dome "
                                f"cannot rise beyond the {probe:g} mm aperture; or is the "
                                "probe wrong?)")
    if a[k] == 0:
        raise MeasuredDataError(path, int(lines[k]), "deflection_mm", f"deflections of the "
                                f"{label} are all 0: no dome was measured")
    if a[k] < max(floor, M_BELOW_MM):
        raise MeasuredDataError(path, int(lines[k]), "deflection_mm", f"largest deflection "
                                f"{d[k]:g} mm looks like metres, not mm (1 m = 1000 mm; a dome "
                                f"under the {probe:g} mm aperture rises by more than "
                                f"{floor * 1e3:g} µm)")
    if d.max() <= 0:
        raise MeasuredDataError(path, int(lines[int(np.argmin(d))]), "deflection_mm",
                                f"deflections of the {label} are negative; give them positive "
                                "into the aperture")


def _check_rise(path, label, lines, t, d, cycles, threshold):
    """The deflection must rise while the suction is on (by more than the noise and
    two quanta: a step of the resolution is not a rise, nor a fall)."""
    for c in cycles:
        before = d[max(0, c.onset - 5):c.onset]
        base = float(np.median(before)) if before.size else 0.0
        top = d[c.hold_start:c.hold_end + 1]
        rise = float(np.median(top[-max(1, top.size // 5):])) - base
        if rise <= threshold:
            k = c.hold_end
            what = "falls" if rise < -threshold else "does not rise"
            raise MeasuredDataError(
                path, int(lines[k]), "deflection_mm",
                f"the {label} {what} when the suction is on (cycle {c.index}, "
                f"{t[c.onset]:g}-{t[c.hold_end]:g} s at {c.level_mbar:.4g} mbar: "
                f"{rise:+.3g} mm against {threshold:.2g} mm of noise and resolution); "
                + ("give deflections positive into the aperture"
                   if rise < -threshold else "is the probe on the skin, the column right?"))
