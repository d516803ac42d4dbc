"""Plausibility of a measured curve: units, sign, zero, growth, size against the aperture.

The rules and why each is an error or a warning are listed in
:mod:`skinsuction.measured`.
"""

from __future__ import annotations

import math

import numpy as np

from ._types import MeasuredDataError, _Rows, _show

#: Largest pressure (mbar) above which a curve "looks like Pa".
PA_ABOVE_MBAR = 1000.0

#: Largest pressure (mbar) at or below which a curve "looks like bar or kPa".
BAR_AT_MOST_MBAR = 1.0

#: Largest |deflection| (mm) above which a curve "looks like µm".
UM_ABOVE_MM = 20.0

#: Largest |deflection| (mm) below which a curve "looks like metres".
M_BELOW_MM = 1e-3

#: A fall of the curve below an earlier deflection is an error when it exceeds this
#: many noise sd of the curve (and a quarter of its span, and 20 µm).
DROP_NOISE_SD = 8.0

#: Fewest points of a curve for its own noise estimate to count in that rule.
DROP_NOISE_POINTS = 20

#: A dome cannot rise beyond the aperture: the largest deflection of a curve must
#: stay below this many aperture diameters ("looks like µm" otherwise).
APERTURE_LIMIT = 1.0

#: ... and above this many diameters, or the curve "looks like metres" (a dome of
#: 6 µm under the 6 mm probe, 2 µm under the 2 mm probe, is below any skin's).
APERTURE_FLOOR = 1e-3

#: Largest pressure (mbar) at or below which a warning says "looks like kPa".
LOW_PRESSURE_MBAR = 20.0


def _label(rows: _Rows) -> str:
    return f"{rows.probe:g} mm curve" + (f" {_show(rows.curve)}" if rows.curve else "")


def _check_curve(path, rows: _Rows) -> list:
    """Check one curve; returns warnings (doubts about data that may be real)."""
    p, d, lines = rows.pressure, rows.deflection, rows.lines
    warnings = []
    if len(p) < 2:
        raise MeasuredDataError(path, lines[0], None, f"the {_label(rows)} has 1 point, need >= 2")
    # negative suction first: 0, -50, -100 also "falls", but its cause is the sign
    k_min = int(np.argmin(p))
    if p[k_min] < 0:
        raise MeasuredDataError(
            path, lines[k_min], "pressure_mbar",
            f"pressure {p[k_min]:g} mbar is negative; give the suction as positive mbar",
        )
    for k in range(1, len(p)):
        if p[k] == p[k - 1]:
            raise MeasuredDataError(
                path, lines[k], "pressure_mbar",
                f"pressure {p[k]:g} mbar repeats line {lines[k - 1]} of the {_label(rows)}",
            )
        if p[k] < p[k - 1]:
            hint = (
                "; a new curve? add a 'curve' column with a replicate id"
                if p[k] <= p[0] else ""
            )
            raise MeasuredDataError(
                path, lines[k], "pressure_mbar",
                f"pressure {p[k]:g} mbar is lower than {p[k - 1]:g} mbar on line {lines[k - 1]}; "
                f"pressures must increase within the {_label(rows)}{hint}",
            )
    # unit rules
    k_max = int(np.argmax(p))
    p_max = p[k_max]
    if p_max > PA_ABOVE_MBAR:
        raise MeasuredDataError(
            path, lines[k_max], "pressure_mbar",
            f"largest pressure {p_max:g} mbar looks like Pa, not mbar "
            "(1 mbar = 100 Pa; a Cutometer applies at most about 500 mbar)",
        )
    if p_max <= 0:
        raise MeasuredDataError(
            path, lines[k_max], "pressure_mbar", f"the {_label(rows)} has no pressure above 0"
        )
    if p_max <= BAR_AT_MOST_MBAR:
        raise MeasuredDataError(
            path, lines[k_max], "pressure_mbar",
            f"largest pressure {p_max:g} mbar looks like bar or kPa, not mbar "
            "(100 mbar = 0.1 bar = 10 kPa)",
        )
    if p_max <= LOW_PRESSURE_MBAR:
        warnings.append(f"{path}: the {_label(rows)} reaches only {p_max:g} mbar (suction "
                        "protocols apply 50-500 mbar): if the file is in kPa, multiply by 10")
    a = np.abs(d)
    k_big = int(np.argmax(a))
    top, floor = APERTURE_LIMIT * rows.probe, APERTURE_FLOOR * rows.probe
    if a[k_big] > min(top, UM_ABOVE_MM):
        raise MeasuredDataError(
            path, lines[k_big], "deflection_mm",
            f"largest deflection {d[k_big]:g} mm looks like µm, not mm (1 mm = 1000 µm; a dome "
            f"cannot rise beyond the {rows.probe:g} mm aperture; or is the probe wrong?)",
        )
    if a[k_big] == 0:
        raise MeasuredDataError(
            path, lines[k_big], "deflection_mm",
            f"deflections of the {_label(rows)} are all 0: no dome was measured")
    if a[k_big] < max(floor, M_BELOW_MM):
        raise MeasuredDataError(
            path, lines[k_big], "deflection_mm",
            f"largest deflection {d[k_big]:g} mm looks like metres, not mm (1 m = 1000 mm; a "
            f"dome under the {rows.probe:g} mm aperture rises by more than {floor * 1e3:g} µm)",
        )
    if max(d) <= 0 and min(d) < 0:
        raise MeasuredDataError(
            path, lines[int(np.argmin(d))], "deflection_mm",
            f"deflections of the {_label(rows)} are negative; "
            "give them positive into the aperture",
        )
    _check_shape(path, rows)
    return warnings


def _noise_sd_mm(p, d) -> float:
    """Noise sd (mm) of one curve from its third differences; 0 below
    :data:`DROP_NOISE_POINTS` points (too few differences to tell noise from a jump)."""
    from skinsuction.noise import noise_from_differences

    if len(p) < DROP_NOISE_POINTS:
        return 0.0
    try:
        return 1e-3 * noise_from_differences([(p, d)]).sd_um
    except ValueError:
        return 0.0


def _check_shape(path, rows: _Rows) -> None:
    """The curve must start at 0 and rise with the pressure (within noise)."""
    p, d, lines = np.asarray(rows.pressure), np.asarray(rows.deflection), rows.lines
    span = float(d.max() - min(d.min(), 0.0))
    if p[0] == 0 and abs(d[0]) > max(0.1 * np.abs(d).max(), 0.01):
        raise MeasuredDataError(
            path, lines[0], "deflection_mm",
            f"deflection {d[0]:g} mm at 0 mbar: the curve must be zeroed at 0 mbar (the "
            "instrument zeroes there); subtract it from the curve")
    # the largest fall below an earlier deflection: noise gives small ones, a curve that
    # falls (wrong sign of the pressure, columns swapped) large ones.  Noise of sd s
    # about a rising curve falls by up to about 5 s over 50 points (a small 2 mm curve
    # of stiff skin with 5 µm of noise: 20-25 µm), so the noise the curve itself shows
    # (third differences, which a smooth curve, falling or not, leaves near 0) counts
    running = np.maximum.accumulate(d)
    drop = running - d
    k = int(np.argmax(drop))
    if drop[k] > max(0.25 * span, 0.02, DROP_NOISE_SD * _noise_sd_mm(p, d)) \
            or np.polyfit(p, d, 1)[0] <= 0:
        j = int(np.argmax(d[:k + 1])) if drop[k] > 0 else 0
        raise MeasuredDataError(
            path, lines[k], "deflection_mm",
            f"the deflection falls with the pressure, from {d[j]:g} mm at {p[j]:g} mbar to "
            f"{d[k]:g} mm at {p[k]:g} mbar; it must grow (columns swapped?)")


def _check_space(path, rows: _Rows, available_probes, pressure_range, range_note=None) -> None:
    if available_probes is not None:
        probes = [float(q) for q in available_probes]
        if not any(math.isclose(rows.probe, q, abs_tol=1e-6) for q in probes):
            listed = ", ".join(f"{q:g}" for q in sorted(probes)) or "none"
            raise MeasuredDataError(
                path, rows.lines[0], "probe_mm",
                f"probe diameter {rows.probe:g} mm is not in the simulated space "
                f"(available: {listed} mm)",
            )
    if pressure_range is not None:
        lo, hi = (float(v) for v in pressure_range)
        for line, p in zip(rows.lines, rows.pressure):
            if p < lo - 1e-9 or p > hi + 1e-9:
                raise MeasuredDataError(
                    path, line, "pressure_mbar",
                    f"pressure {p:g} mbar is outside the simulated range {lo:g}..{hi:g} mbar"
                    + (f" ({range_note})" if range_note else ""),
                )
