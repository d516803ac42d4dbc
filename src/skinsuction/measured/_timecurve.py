"""Cutometer time curves: deflection and suction against time (mode 1, mode 2, any p(t)).

File format
-----------
The measured-curve format of :mod:`skinsuction.measured` with a time column::

    # subject: S01
    probe_mm,time_s,pressure_mbar,deflection_mm,curve
    6,0.00,0,0.00,A
    6,0.01,401,0.31,A
    ...

* Columns ``probe_mm`` (mm), ``time_s`` (s, any origin), ``pressure_mbar`` (suction,
  positive, mbar) and ``deflection_mm`` (mm, positive into the aperture, zeroed before
  the first suction as the device does) are required, ``curve`` (replicate id) is
  optional; ``#`` lines, ``key: value`` metadata and the layer thicknesses are read
  exactly as for pressure ramps.  A curve is the rows of one (``probe_mm``, ``curve``).
* :func:`is_time_curve_file` tells the two formats apart (a ``time_s`` column).

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

Errors
------
Every rejection is a :class:`MeasuredDataError` naming the file, the line and the
column: a header or a number as for pressure ramps; fewer than
:data:`MIN_SAMPLES` samples in a curve; a time not after the one before; a pressure
below zero beyond the sensor's noise, above :data:`DEVICE_MAX_MBAR` (above 1000: looks
like Pa) or at most 1 (looks like bar or kPa); deflections in µm or m, all zero or
negative; no suction; a hold of fewer than 3 samples; a curve that does not rise when
the suction is on.  A low largest pressure (<= 20 mbar) is a warning.

Examples
--------
>>> import pathlib, tempfile
>>> import numpy as np
>>> t = np.round(np.arange(0, 10, 0.01), 2)
>>> on = (t % 5 >= 0.5) & (t % 5 < 3.5)          # 3 s on / 2 s off, twice
>>> d = np.round(on * (0.4 + 0.1 * (t % 5 - 0.5) / 3), 2)   # jump, creep; 0.01 mm steps
>>> rows = [f"6,{ti:.2f},{400 * o:g},{di:.2f}" for ti, o, di in zip(t, on, d)]
>>> path = pathlib.Path(tempfile.mkdtemp()) / "mode1.csv"
>>> _ = path.write_text("probe_mm,time_s,pressure_mbar,deflection_mm\\n"
...                     + "\\n".join(rows) + "\\n")
>>> is_time_curve_file(path)
True
>>> c = load_time_curves(path).curve(6)
>>> c.protocol, len(c.cycles), c.resolution_mm
('mode 1', 2, 0.01)
>>> [(float(c.time_s[k.onset]), float(c.time_s[k.release])) for k in c.cycles]
[(0.5, 3.5), (5.5, 8.5)]
>>> c.noise_sd_mm >= 0.01 / 12 ** 0.5
True
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field

import numpy as np

from ._checks import APERTURE_FLOOR, APERTURE_LIMIT, BAR_AT_MOST_MBAR, LOW_PRESSURE_MBAR, \
    M_BELOW_MM, PA_ABOVE_MBAR, UM_ABOVE_MM
from ._geometry import check_geometry_metadata
from ._load import _comment, _header, _lines, _number, _read_text, _split
from ._types import MeasuredDataError, _show

__all__ = ["TIME_REQUIRED_COLUMNS", "TIME_OPTIONAL_COLUMNS", "MIN_SAMPLES",
           "MAX_SAMPLES_PER_CURVE", "DEVICE_MAX_MBAR", "SETTLE_S", "Cycle", "TimeCurve",
           "MeasuredTimeData", "load_time_curves", "is_time_curve_file"]

TIME_REQUIRED_COLUMNS = ("probe_mm", "time_s", "pressure_mbar", "deflection_mm")

TIME_OPTIONAL_COLUMNS = ("curve",)

#: Fewest samples of a curve: fewer cannot show a suction, a hold and a release.
MIN_SAMPLES = 20

#: Most samples of a curve (200 s at 1 kHz): beyond, a wrong file fails fast.
MAX_SAMPLES_PER_CURVE = 200_000

#: Largest suction of the device range (mbar): a Cutometer applies at most about
#: 500 mbar; above 1000 a file "looks like Pa".
DEVICE_MAX_MBAR = 600.0

#: Seconds after a phase starts that the noise estimate skips (the 10 ms creep term
#: has settled to e^-10 of its size).
SETTLE_S = 0.1

_TIME_HINTS = {
    "time_ms": "times must be in s: name the column time_s and divide ms by 1000",
    "time": "name the time column time_s (in seconds)",
    "t_s": "name the time column time_s (in seconds)",
}

# the switch of the suction (fractions of the largest filtered pressure P)
_ON_FRACTION, _OFF_FRACTION, _BAND_FRACTION = 0.3, 0.02, 0.03
# a step rises and releases within this fraction of its cycle; a ramp takes at least
# _RAMP_FRACTION on each side
_STEP_FRACTION, _RAMP_FRACTION, _HOLD_IN_BAND = 0.10, 0.25, 0.90
# a rise below this many noise sd (and 2 quanta) is "does not rise"
_RISE_NOISE_SD = 4.0


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


@dataclass(frozen=True, eq=False)
class TimeCurve:
    """One time curve (a probe and a curve id) with its phases, resolution and noise.

    Attributes
    ----------
    probe_mm : float
    time_s, pressure_mbar, deflection_mm : ndarray
        The samples, time strictly increasing.
    curve : str
        Replicate id ('' without a ``curve`` column).
    lines : ndarray of int
        The file's line of each sample (for located errors).
    cycles : tuple of Cycle
    protocol : str
        ``"mode 1"``, ``"mode 2"`` or ``"other"``.
    resolution_mm : float or None
        The deflection's resolution (0.01 mm on a Cutometer), None if not on a grid.
    noise_sd_mm : float
        Noise sd of one deflection, not below ``quantisation_sd_mm``.
    quantisation_sd_mm : float
        ``resolution_mm / sqrt(12)`` (0 without a resolution).
    pressure_noise_mbar : float
        Noise sd of the pressure (from its second differences).
    notes : tuple of str
        Facts about the curve (resolution, noise, protocol), not doubts.
    """

    probe_mm: float
    time_s: np.ndarray
    pressure_mbar: np.ndarray
    deflection_mm: np.ndarray
    curve: str = ""
    lines: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    cycles: tuple = ()
    protocol: str = "other"
    resolution_mm: float | None = None
    noise_sd_mm: float = 0.0
    quantisation_sd_mm: float = 0.0
    pressure_noise_mbar: float = 0.0
    notes: tuple = ()

    def __len__(self) -> int:
        return int(self.time_s.size)

    @property
    def first_line(self) -> int:
        return int(self.lines[0]) if self.lines.size else 0

    @property
    def label(self) -> str:
        return f"{self.probe_mm:g} mm curve" + (f" {_show(self.curve)}" if self.curve else "")

    def phases(self) -> np.ndarray:
        """The phase of every sample: ``"off"``, ``"rise"``, ``"hold"``, ``"release"``."""
        out = np.full(len(self), "off", dtype=object)
        for c in self.cycles:
            stop = c.off if c.off is not None else len(self)
            out[c.onset:c.hold_start] = "rise"
            out[c.hold_start:c.hold_end + 1] = "hold"
            out[c.release:stop] = "release"
        return out


@dataclass(frozen=True, eq=False)
class MeasuredTimeData:
    """Every time curve of one file, with its comments.

    Attributes
    ----------
    path : str
    curves : tuple of TimeCurve
        In the order of their first row.
    metadata : dict
    comments : tuple of str
    warnings : tuple of str
        Doubts about data that may still be real.
    notes : tuple of str
        Facts about the curves (protocol, resolution, noise).
    geometry : dict
        The layer thicknesses of the header, checked (see :func:`check_geometry_metadata`).
    """

    path: str
    curves: tuple
    metadata: dict = field(default_factory=dict)
    comments: tuple = ()
    warnings: tuple = ()
    notes: tuple = ()
    geometry: dict = field(default_factory=dict)

    @property
    def probes(self) -> tuple:
        """Probe diameters present in the file, ascending."""
        return tuple(sorted({c.probe_mm for c in self.curves}))

    def for_probe(self, probe_mm: float) -> tuple:
        return tuple(c for c in self.curves if math.isclose(c.probe_mm, probe_mm, abs_tol=1e-6))

    def curve(self, probe_mm: float, curve: str | None = None) -> TimeCurve:
        """The single curve of a probe, or the replicate named ``curve`` (KeyError if
        none or several match)."""
        found = self.for_probe(probe_mm)
        if curve is not None:
            found = tuple(c for c in found if c.curve == str(curve))
        if len(found) != 1:
            raise KeyError(f"{self.path}: {len(found)} time curves match probe {probe_mm:g} mm"
                           f"{'' if curve is None else f', curve {curve!r}'}")
        return found[0]


# ------------------------------------------------------------------ reading
def is_time_curve_file(path) -> bool:
    """True if the file's header line (the first line that is neither blank nor a
    ``#`` comment) has a ``time_s`` column; False otherwise or if it cannot be read
    (the loaders then say why).

    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "ramp.csv"
    >>> _ = path.write_text("# a ramp\\nprobe_mm,pressure_mbar,deflection_mm\\n6,0,0\\n")
    >>> is_time_curve_file(path)
    False
    """
    try:
        with open(path, "rb") as f:
            head = f.read(1 << 16)
    except OSError:
        return False
    return _has_time_column(head.decode("utf-8-sig", errors="replace"))


def _has_time_column(text: str) -> bool:
    """The one rule telling the formats apart: the header line has a ``time_s`` column
    (used by :func:`is_time_curve_file` and :func:`skinsuction.measured.read_measurement`)."""
    for line in _lines(text):
        stripped = line.strip()
        if stripped and not stripped.startswith("#"):
            return "time_s" in _split(stripped)
    return False


def load_time_curves(path: str | os.PathLike) -> MeasuredTimeData:
    """Read and check a time-curve CSV file, find its phases, resolution and noise.

    Parameters
    ----------
    path : str or path-like
        A file in the format of the module docstring.

    Returns
    -------
    MeasuredTimeData

    Raises
    ------
    MeasuredDataError
        For any problem of the file, with file, line and column in the message.
    """
    try:
        return _load(path)
    except MeasuredDataError as err:
        if err.column == "time_s" and err.reason.startswith("required column is missing"):
            # the commonest mix-up: a pressure ramp M(p) given where time curves are read
            raise MeasuredDataError(err.path, err.line, err.column, err.reason + " (a pressure "
                                    "ramp M(p)? time curves have probe_mm,time_s,"
                                    "pressure_mbar,deflection_mm)") from None
        raise


def _load(path, text=None) -> MeasuredTimeData:
    """The time curves of a file; ``text``: its content if already read."""
    text = _read_text(path) if text is None else text
    comments, metadata, meta_lines, header, groups = [], {}, {}, None, {}
    lines = _lines(text)
    for lineno, line in enumerate(lines, start=1):
        stripped = line.strip()
        if not stripped:
            continue
        if stripped.startswith("#"):
            _comment(stripped, lineno, comments, metadata, meta_lines)
            continue
        if header is None:
            header = _header(path, lineno, line, required=TIME_REQUIRED_COLUMNS,
                             optional=TIME_OPTIONAL_COLUMNS, hints=_TIME_HINTS)
            continue
        fields = _split(line)
        if len(fields) != len(header):
            hint = " (a decimal comma? use '.')" if len(fields) > len(header) else ""
            raise MeasuredDataError(path, lineno, None, f"found {len(fields)} fields, expected "
                                    f"{len(header)} ({', '.join(header)}){hint}")
        row = dict(zip(header, fields))
        values = [_number(path, lineno, c, row[c]) for c in TIME_REQUIRED_COLUMNS]
        if values[0] <= 0:
            raise MeasuredDataError(path, lineno, "probe_mm",
                                    f"probe diameter {values[0]:g} mm must be positive")
        curve = row.get("curve", "")
        if "curve" in row and curve == "":
            raise MeasuredDataError(path, lineno, "curve", "curve id is empty")
        rows = groups.setdefault((values[0], curve), [])
        if len(rows) >= MAX_SAMPLES_PER_CURVE:
            raise MeasuredDataError(path, lineno, None, f"the {values[0]:g} mm curve has more "
                                    f"than {MAX_SAMPLES_PER_CURVE} samples (split the file)")
        rows.append((lineno, *values[1:]))
    if header is None:
        raise MeasuredDataError(path, len(lines), None, "no header line (expected "
                                + ",".join(TIME_REQUIRED_COLUMNS) + ")")
    if not groups:
        raise MeasuredDataError(path, len(lines), None, "no data rows after the header")
    geometry = check_geometry_metadata(path, metadata, meta_lines)
    curves, warnings, notes = [], [], []
    for (probe, curve), rows in groups.items():
        arr = np.array(rows, dtype=float)
        c, w = _build(path, probe, curve, arr[:, 0].astype(int), arr[:, 1], arr[:, 2],
                      arr[:, 3])
        curves.append(c)
        warnings += w
        notes += [f"{c.label}: {n}" for n in c.notes]
    return MeasuredTimeData(str(path), tuple(curves), metadata, tuple(comments),
                            tuple(warnings), tuple(notes), geometry)


# ------------------------------------------------------------------ checks
def _build(path, probe, curve, lines, t, p, d):
    label = f"{probe:g} mm curve" + (f" {_show(curve)}" if curve else "")
    if t.size < MIN_SAMPLES:
        raise MeasuredDataError(path, int(lines[-1]), None, f"the {label} has {t.size} "
                                f"samples; need >= {MIN_SAMPLES} (a suction, its hold and its "
                                "release)")
    _check_time(path, label, lines, t)
    warnings = _check_pressure(path, label, lines, p)
    _check_deflection(path, label, probe, lines, d)
    p_sd = _pressure_noise(p)
    cycles = _find_cycles(t, p, p_sd)
    if not cycles:
        k = int(np.argmax(p))
        raise MeasuredDataError(path, int(lines[k]), "pressure_mbar", f"the {label} has no "
                                f"suction lasting more than 2 samples (largest {p[k]:g} mbar): "
                                "spikes only, or sampled too slowly to show a hold (need >= 3 "
                                "samples of it; sample faster)")
    for c in cycles:
        if c.kind == "step" and c.hold_end - c.hold_start + 1 < 3:
            raise MeasuredDataError(path, int(lines[c.hold_start]), "time_s", f"the hold of "
                                    f"cycle {c.index} of the {label} has "
                                    f"{c.hold_end - c.hold_start + 1} samples; need >= 3 "
                                    "(sample faster)")
    protocol = _protocol(cycles)
    q = grid_step(d)
    q_sd = q / math.sqrt(12.0) if q else 0.0
    raw_sd = _noise_sd(t, d, cycles)
    noise_sd = max(raw_sd, q_sd)
    _check_rise(path, label, lines, t, d, cycles, max(_RISE_NOISE_SD * noise_sd, 2 * (q or 0)))
    notes = [_protocol_note(protocol, cycles, t)]
    if q:
        notes.append(f"deflection resolution {q:g} mm: steps of {q:g} mm are quantisation, "
                     f"not noise or misfit (their sd q/sqrt(12) = {1e3 * q_sd:.2g} µm)")
    notes.append(f"noise sd {1e3 * noise_sd:.2g} µm ("
                 + (f"the quantisation floor; the differences show {1e3 * raw_sd:.2g} µm"
                    if raw_sd < q_sd else "third differences within the phases")
                 + f"); pressure noise sd {p_sd:.2g} mbar")
    tc = TimeCurve(float(probe), t, p, d, curve, lines, tuple(cycles), protocol, q, noise_sd,
                   q_sd, p_sd, tuple(notes))
    return tc, warnings + _baseline_warning(path, tc)


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


def _baseline_warning(path, c: TimeCurve) -> list:
    first = c.cycles[0].onset
    if first == 0:
        return []
    base = float(np.median(c.deflection_mm[:first]))
    if abs(base) > max(0.01, 2 * (c.resolution_mm or 0), 3 * c.noise_sd_mm):
        return [f"{path}: the {c.label} is not zeroed before its first suction (deflection "
                f"{base:g} mm there): R values of its first cycle are read from the file's "
                "zero"]
    return []


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
    """The deflection's grid step: the smallest gap between distinct values, if every
    value is a whole multiple of it (to 2 % of a step) and the range spans at least
    ``min_steps`` steps (to read a resolution off a file, 20: two levels 0.5 mm apart
    are a square wave, not a resolution); None otherwise or below 1e-6 mm."""
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
