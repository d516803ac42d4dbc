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

Phases, protocol, resolution and noise
--------------------------------------
The loader finds the cycles of the suction (rise, hold, release, off), the protocol
(``"mode 1"``, ``"mode 2"`` or ``"other"``), the deflection's resolution and its noise
sd: how, in :mod:`._phases`.

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

from ._geometry import check_geometry_metadata
from ._load import _comment, _header, _lines, _number, _read_text, _split
from ._phases import SETTLE_S, Cycle, _find_cycles, _noise_sd, _pressure_noise, _protocol, \
    _protocol_note, grid_step
from ._timecheck import DEVICE_MAX_MBAR, _RISE_NOISE_SD, _check_deflection, _check_pressure, \
    _check_rise, _check_time
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

_TIME_HINTS = {
    "time_ms": "times must be in s: name the column time_s and divide ms by 1000",
    "time": "name the time column time_s (in seconds)",
    "t_s": "name the time column time_s (in seconds)",
}


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


# ------------------------------------------------------------------ one curve, checked
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
