"""Load and check measured suction curves M(p) (CSV files).

File format
-----------
UTF-8 text (a byte-order mark is allowed), comma-separated, one header line::

    # subject: S01
    # site: forearm
    probe_mm,pressure_mbar,deflection_mm,curve
    6,0,0.000,A
    6,2,0.031,A
    ...

* Columns ``probe_mm`` (aperture diameter, mm), ``pressure_mbar`` (suction,
  positive, mbar) and ``deflection_mm`` (apex deflection into the aperture, mm)
  are required; ``curve`` (replicate id, any text) is optional.  No other column
  is allowed; the order of the columns is free.
* Lines starting with ``#`` are comments, kept in ``MeasuredData.comments``;
  ``# key: value`` comments also go to ``MeasuredData.metadata`` (a later key
  overrides an earlier one).  Blank lines are ignored.
* One file may hold several probes and several curves per probe.  A curve is
  the set of rows with the same (``probe_mm``, ``curve``); without a ``curve``
  column every probe has exactly one curve.  Within a curve the pressures must
  strictly increase down the file.

Every rejection raises :class:`MeasuredDataError` (a ``ValueError``) with a
one-line message naming the file, the line (1-based, counting every line of the
file) and, where it applies, the column.  The checks, in this order:

1. the file can be read and is UTF-8;
2. header: comma-separated, no missing, unknown or repeated column;
3. every row: as many fields as the header; numbers in plain decimal notation
   (``1``, ``-0.5``, ``2e-3``), finite; ``probe_mm > 0``; ``curve`` not empty;
4. every curve: at least 2 points, pressures strictly increasing (a drop
   suggests two curves without a ``curve`` column), then the unit rules below;
5. against the simulated space, if given: the probe diameter is one of
   ``available_probes`` (to 1e-6 mm); the pressures lie in
   ``pressure_range_mbar`` (to 1e-9 mbar).

Unit and plausibility rules, per curve (a Cutometer applies at most about
500 mbar, and a dome cannot rise beyond its aperture):

* pressures below zero: suction must be given as positive mbar (checked first:
  0, -50, -100 mbar is a sign, not a new curve);
* largest pressure above 1000 "mbar": looks like Pa (1 mbar = 100 Pa);
* largest pressure above 0 but at most 1 "mbar": looks like bar or kPa
  (100 mbar = 0.1 bar = 10 kPa);
* no pressure above 0: a curve needs suction;
* largest pressure at most 20 mbar: a *warning* only (``MeasuredData.warnings``):
  protocols apply 50-500 mbar and the file may be in kPa, but a low-pressure
  protocol is possible;
* largest |deflection| above the aperture diameter (or 20 mm): looks like µm;
* all deflections 0: no dome was measured;
* largest |deflection| below 1/1000 of the aperture diameter (6 µm under the
  6 mm probe, 2 µm under the 2 mm one) or 0.001 mm: looks like metres;
* deflections all <= 0 with some < 0: wrong sign (positive into the aperture);
* a deflection at 0 mbar above 10 % of the largest and 0.01 mm: the curve must
  be zeroed there (the instrument zeroes at 0 mbar);
* a fall of the deflection below an earlier one by more than a quarter of the
  curve's span and 0.02 mm, or a falling trend: it must grow with the pressure
  (noise makes only small falls).

Sizes: at most 2 000 points per curve, 2 000 000 lines and 256 MB per file, so
that a wrong file fails fast instead of filling the memory.

Examples
--------
>>> import pathlib, tempfile
>>> path = pathlib.Path(tempfile.mkdtemp()) / "s01.csv"
>>> _ = path.write_text("# subject: S01\\nprobe_mm,pressure_mbar,deflection_mm\\n"
...                     "6,0,0\\n6,50,0.4\\n6,100,0.7\\n", encoding="utf-8")
>>> data = load_measured(path, available_probes=[2, 6], pressure_range_mbar=(0, 100))
>>> data.metadata["subject"], data.probes
('S01', (6.0,))
>>> data.curve(6).deflection_mm.tolist()
[0.0, 0.4, 0.7]
>>> _ = path.write_text("probe_mm,pressure_mbar,deflection_mm\\n6,0,0\\n6,5000,400\\n")
>>> load_measured(path)  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
skinsuction.measured.MeasuredDataError: ...s01.csv, line 3, column 'pressure_mbar': largest pressure 5000 mbar looks like Pa, not mbar (1 mbar = 100 Pa; a Cutometer applies at most about 500 mbar)
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "MeasuredDataError",
    "MeasuredCurve",
    "MeasuredData",
    "load_measured",
    "REQUIRED_COLUMNS",
    "OPTIONAL_COLUMNS",
    "StudyEntry",
    "load_table",
]

REQUIRED_COLUMNS = ("probe_mm", "pressure_mbar", "deflection_mm")
OPTIONAL_COLUMNS = ("curve",)

#: Largest pressure (mbar) above which a curve "looks like Pa".
PA_ABOVE_MBAR = 1000.0
#: Largest pressure (mbar) at or below which a curve "looks like bar or kPa".
BAR_AT_MOST_MBAR = 1.0
#: Largest |deflection| (mm) above which a curve "looks like µm".
UM_ABOVE_MM = 20.0
#: Largest |deflection| (mm) below which a curve "looks like metres".
M_BELOW_MM = 1e-3
#: A dome cannot rise beyond the aperture: the largest deflection of a curve must
#: stay below this many aperture diameters ("looks like µm" otherwise).
APERTURE_LIMIT = 1.0
#: ... and above this many diameters, or the curve "looks like metres" (a dome of
#: 6 µm under the 6 mm probe, 2 µm under the 2 mm probe, is below any skin's).
APERTURE_FLOOR = 1e-3
#: Largest pressure (mbar) at or below which a warning says "looks like kPa".
LOW_PRESSURE_MBAR = 20.0
#: Points per curve and rows per file: beyond them a file is refused before it
#: fills the memory (a Cutometer curve has tens to hundreds of points).
MAX_POINTS_PER_CURVE = 2_000
MAX_ROWS_PER_FILE = 2_000_000
MAX_FILE_BYTES = 256 * 2 ** 20

_NUMBER = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
_NON_FINITE = re.compile(r"[+-]?(?:nan|inf|infinity)", re.IGNORECASE)
_UNIT_HINTS = {
    "pressure_pa": "pressures must be in mbar: name the column pressure_mbar and divide Pa by 100",
    "pressure_kpa": "pressures must be in mbar: name the column pressure_mbar and multiply kPa by 10",
    "pressure_bar": "pressures must be in mbar: name the column pressure_mbar and multiply bar by 1000",
    "deflection_um": "deflections must be in mm: name the column deflection_mm and divide µm by 1000",
    "deflection_µm": "deflections must be in mm: name the column deflection_mm and divide µm by 1000",
    "deflection_m": "deflections must be in mm: name the column deflection_mm and multiply m by 1000",
    "probe_cm": "the probe diameter must be in mm: name the column probe_mm",
}


class MeasuredDataError(ValueError):
    """A measured-curve file was rejected; the message is one line.

    Attributes
    ----------
    path : str
    line : int or None
        1-based line of the file.
    column : str or None
    reason : str
    """

    def __init__(self, path, line: int | None, column: str | None, reason: str):
        self.path = str(path)
        self.line = line
        self.column = column
        self.reason = " ".join(str(reason).split())  # one line, whatever the input
        where = self.path
        if line is not None:
            where += f", line {line}"
        if column is not None:
            where += f", column {_show(column)}"
        super().__init__(f"{where}: {self.reason}")


@dataclass(frozen=True, eq=False)
class MeasuredCurve:
    """One measured curve M(p).

    Attributes
    ----------
    probe_mm : float
    pressure_mbar, deflection_mm : ndarray
        Strictly increasing pressures and the deflections measured at them.
    curve : str
        Replicate id ('' when the file has no ``curve`` column).
    first_line : int
        Line of the file where the curve starts.
    """

    probe_mm: float
    pressure_mbar: np.ndarray
    deflection_mm: np.ndarray
    curve: str = ""
    first_line: int = 0

    def __len__(self) -> int:
        return int(self.pressure_mbar.size)


@dataclass(frozen=True, eq=False)
class MeasuredData:
    """Every curve of one file, with its comments.

    Attributes
    ----------
    path : str
    curves : tuple of MeasuredCurve
        In the order of their first row in the file.
    metadata : dict
        ``key: value`` comments.
    comments : tuple of str
        Every comment line, without the leading ``#`` and surrounding blanks.
    warnings : tuple of str
        Doubts about data that may still be real (e.g. a low largest pressure).
    """

    path: str
    curves: tuple
    metadata: dict = field(default_factory=dict)
    comments: tuple = ()
    warnings: tuple = ()

    @property
    def probes(self) -> tuple:
        """Probe diameters present in the file, ascending."""
        return tuple(sorted({c.probe_mm for c in self.curves}))

    def for_probe(self, probe_mm: float) -> tuple:
        """All curves (replicates) of one probe."""
        return tuple(c for c in self.curves if math.isclose(c.probe_mm, probe_mm, abs_tol=1e-6))

    def curve(self, probe_mm: float, curve: str | None = None) -> MeasuredCurve:
        """The single curve of a probe, or the replicate named ``curve``.

        Raises
        ------
        KeyError
            If there is no such curve, or several and ``curve`` is None.
        """
        found = self.for_probe(probe_mm)
        if curve is not None:
            found = tuple(c for c in found if c.curve == str(curve))
        if len(found) != 1:
            ids = [c.curve for c in self.for_probe(probe_mm)]
            raise KeyError(
                f"{self.path}: {len(found)} curves match probe {probe_mm:g} mm"
                f"{'' if curve is None else f', curve {curve!r}'} (curves of this probe: {ids})"
            )
        return found[0]


def _show(value, limit: int = 40) -> str:
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _read_text(path) -> str:
    try:
        size = os.path.getsize(path)
        if size > MAX_FILE_BYTES:
            raise MeasuredDataError(path, None, None, f"the file has {size / 2 ** 20:.0f} MB; at "
                                    f"most {MAX_FILE_BYTES // 2 ** 20} MB are read (split it)")
        with open(path, "rb") as f:
            raw = f.read()
    except OSError as e:
        raise MeasuredDataError(path, None, None, f"cannot read the file ({e.strerror or e})") from None
    rows = raw.count(b"\n")
    if rows > MAX_ROWS_PER_FILE:
        raise MeasuredDataError(path, None, None, f"the file has {rows} lines; at most "
                                f"{MAX_ROWS_PER_FILE} are read (split it)")
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        line = raw[: e.start].count(b"\n") + 1
        raise MeasuredDataError(
            path, line, None, f"not UTF-8 text (byte 0x{raw[e.start]:02x}); save the file as UTF-8"
        ) from None


def _split(line: str) -> list[str]:
    return [f.strip().strip('"').strip() for f in line.split(",")]


def _header(path, lineno: int, text: str, extra_columns: bool = False) -> list[str]:
    names = _split(text)
    if len(names) == 1:
        for sep, label in ((";", "';'"), ("\t", "tabs")):
            if sep in text:
                raise MeasuredDataError(
                    path, lineno, None,
                    f"columns must be separated by ',', the header uses {label}",
                )
    seen = set()
    for name in names:
        if name in seen:
            raise MeasuredDataError(path, lineno, name, "column appears twice in the header")
        seen.add(name)
        if name == "":
            raise MeasuredDataError(path, lineno, None, "a column of the header has no name")
        if name not in REQUIRED_COLUMNS + OPTIONAL_COLUMNS and not (
                extra_columns and name.lower() not in _UNIT_HINTS):
            hint = _UNIT_HINTS.get(name.lower())
            if hint is None:
                hint = (
                    "unexpected column; the columns are "
                    + ", ".join(REQUIRED_COLUMNS)
                    + " and optionally "
                    + ", ".join(OPTIONAL_COLUMNS)
                )
            raise MeasuredDataError(path, lineno, name, hint)
    for name in REQUIRED_COLUMNS:
        if name not in seen:
            raise MeasuredDataError(path, lineno, name, "required column is missing from the header")
    return names


def _number(path, lineno: int, column: str, text: str) -> float:
    if _NUMBER.fullmatch(text):
        value = float(text)
        if math.isfinite(value):
            return value
        raise MeasuredDataError(path, lineno, column, f"value {_show(text)} is too large")
    if _NON_FINITE.fullmatch(text):
        raise MeasuredDataError(path, lineno, column, f"value {_show(text)} is not finite")
    if text == "":
        raise MeasuredDataError(path, lineno, column, "value is empty")
    raise MeasuredDataError(path, lineno, column, f"value {_show(text)} is not a number")


@dataclass
class _Rows:
    probe: float
    curve: str
    lines: list = field(default_factory=list)
    pressure: list = field(default_factory=list)
    deflection: list = field(default_factory=list)


def _lines(text: str):
    """The lines of a text: LF, CRLF or CR-only (old Mac) line ends."""
    return text.replace("\r\n", "\n").replace("\r", "\n").split("\n")


def _parse(path, text: str, line_numbers=None):
    comments, metadata, header, groups = [], {}, None, {}
    lines = _lines(text)
    numbers = range(1, len(lines) + 1) if line_numbers is None else line_numbers
    for lineno, line in zip(numbers, lines):
        line = line.rstrip("\r")
        stripped = line.strip()
        if not stripped:
            continue
        if stripped.startswith("#"):
            comment = stripped[1:].strip()
            comments.append(comment)
            key, sep, value = comment.partition(":")
            if sep and key.strip():
                metadata[key.strip()] = value.strip()
            continue
        if header is None:
            header = _header(path, lineno, line)
            continue
        fields = _split(line)
        if len(fields) != len(header):
            hint = " (a decimal comma? use '.')" if len(fields) > len(header) else ""
            raise MeasuredDataError(
                path, lineno, None,
                f"found {len(fields)} fields, expected {len(header)} ({', '.join(header)}){hint}",
            )
        row = dict(zip(header, fields))
        values = {c: _number(path, lineno, c, row[c]) for c in REQUIRED_COLUMNS}
        if values["probe_mm"] <= 0:
            raise MeasuredDataError(
                path, lineno, "probe_mm", f"probe diameter {values['probe_mm']:g} mm must be positive"
            )
        curve = row.get("curve", "")
        if "curve" in row and curve == "":
            raise MeasuredDataError(path, lineno, "curve", "curve id is empty")
        key = (values["probe_mm"], curve)
        rows = groups.setdefault(key, _Rows(values["probe_mm"], curve))
        if len(rows.lines) >= MAX_POINTS_PER_CURVE:
            raise MeasuredDataError(
                path, lineno, None,
                f"the {_label(rows)} has more than {MAX_POINTS_PER_CURVE} points; a suction "
                "curve has tens to hundreds (split replicates with a 'curve' column)")
        rows.lines.append(lineno)
        rows.pressure.append(values["pressure_mbar"])
        rows.deflection.append(values["deflection_mm"])
    last = numbers[-1] if len(numbers) else 1
    if header is None:
        raise MeasuredDataError(
            path, last, None,
            "no header line (expected " + ",".join(REQUIRED_COLUMNS) + ")",
        )
    if not groups:
        raise MeasuredDataError(path, last, None, "no data rows after the header")
    return header, groups, comments, metadata


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
    # falls (wrong sign of the pressure, columns swapped) large ones
    running = np.maximum.accumulate(d)
    drop = running - d
    k = int(np.argmax(drop))
    if drop[k] > max(0.25 * span, 0.02) or np.polyfit(p, d, 1)[0] <= 0:
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


def load_measured(
    path: str | os.PathLike,
    *,
    available_probes=None,
    pressure_range_mbar=None,
    range_note: str | None = None,
) -> MeasuredData:
    """Read and check a measured-curve CSV file (format in the module docstring).

    Parameters
    ----------
    path : str or path-like
    available_probes : iterable of float, optional
        Probe diameters (mm) held by the simulated space; other probes are rejected.
    pressure_range_mbar : (float, float), optional
        Pressure range of the simulated space; pressures outside are rejected.
    range_note : str, optional
        What sets that range (e.g. the reach of the scale-free space), for the error.

    Returns
    -------
    MeasuredData

    Raises
    ------
    MeasuredDataError
        For any problem of the file, with file, line and column in the message.
    """
    return _load_text(path, _read_text(path), None, available_probes, pressure_range_mbar,
                      range_note)


def _load_text(path, text, line_numbers, available_probes=None, pressure_range_mbar=None,
               range_note=None, metadata=None) -> MeasuredData:
    _, groups, comments, file_metadata = _parse(path, text, line_numbers)
    metadata = {**file_metadata, **(metadata or {})}
    warnings = []
    for rows in groups.values():
        warnings += _check_curve(path, rows)
    for rows in groups.values():
        _check_space(path, rows, available_probes, pressure_range_mbar, range_note)
    curves = tuple(
        MeasuredCurve(
            probe_mm=rows.probe,
            pressure_mbar=np.array(rows.pressure),
            deflection_mm=np.array(rows.deflection),
            curve=rows.curve,
            first_line=rows.lines[0],
        )
        for rows in groups.values()
    )
    return MeasuredData(str(path), curves, metadata, tuple(comments), tuple(warnings))


@dataclass(frozen=True, eq=False)
class StudyEntry:
    """One measurement of a study: its ids and its curves, or the error that stopped it.

    Attributes
    ----------
    ids : dict
        Id columns of a long CSV, ``# key: value`` lines and manifest entries.
    data : MeasuredData or None
    error : str or None
        The one-line message of a rejected measurement (file, line, column).
    source : str
        The file it comes from.
    """

    ids: dict
    data: MeasuredData | None
    error: str | None
    source: str


def load_table(path, *, ids=None, available_probes=None, pressure_range_mbar=None,
               range_note=None) -> list:
    """Read a measured CSV whose extra columns are ids: one :class:`StudyEntry` per id value.

    Columns other than ``probe_mm``, ``pressure_mbar``, ``deflection_mm`` and
    ``curve`` (e.g. ``subject``, ``site``, ``visit``, ``group``) are ids: the
    rows with the same ids form one measurement, checked by the rules of
    :func:`load_measured` with the file's own line numbers.  A file without id
    columns is one measurement.  A bad row stops only its measurement (or, if
    its ids cannot be read, becomes an entry of its own): a study goes on.

    Parameters
    ----------
    ids : dict, optional
        Ids of the whole file (e.g. from a manifest); its id columns and
        ``# key: value`` lines add to them.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "study.csv"
    >>> _ = path.write_text("subject,visit,probe_mm,pressure_mbar,deflection_mm\\n"
    ...                     "S1,1,6,0,0\\nS1,1,6,100,0.7\\nS2,1,6,0,0\\nS2,1,6,100,0,8\\n")
    >>> [(e.ids["subject"], e.error is None) for e in load_table(path)]
    [('S1', True), ('S2', False)]
    >>> print(load_table(path)[1].error)  # doctest: +ELLIPSIS
    /...study.csv, line 5: found 6 fields, expected 5 (...) (a decimal comma? use '.')
    """
    try:
        text = _read_text(path)
    except MeasuredDataError as err:
        return [StudyEntry(dict(ids or {}), None, str(err), str(path))]
    lines = _lines(text)
    header, comments = None, []
    for lineno, line in enumerate(lines, start=1):
        stripped = line.strip()
        if stripped.startswith("#"):
            comments.append((lineno, line))
        elif stripped:
            header = (lineno, line)
            break
    meta = {}
    for _, c in comments:
        key, sep, value = c.strip()[1:].strip().partition(":")
        if sep and key.strip():
            meta[key.strip()] = value.strip()
    base_ids = {**meta, **(ids or {})}
    if header is None:
        return [StudyEntry(base_ids, None, str(MeasuredDataError(
            path, len(lines), None, "no header line (expected " + ",".join(REQUIRED_COLUMNS)
            + ")")), str(path))]
    try:
        names = _header(path, header[0], header[1], extra_columns=True)
    except MeasuredDataError as err:
        return [StudyEntry(base_ids, None, str(err), str(path))]
    id_cols = [i for i, n in enumerate(names) if n not in REQUIRED_COLUMNS + OPTIONAL_COLUMNS]
    kept = [i for i in range(len(names)) if i not in id_cols]
    sub_header = ",".join(names[i] for i in kept)
    groups, bad = {}, []
    for lineno in range(header[0] + 1, len(lines) + 1):
        line = lines[lineno - 1]
        stripped = line.strip()
        if not stripped or stripped.startswith("#"):
            continue
        fields = _split(line)
        if len(fields) != len(names):
            hint = " (a decimal comma? use '.')" if len(fields) > len(names) else ""
            key = tuple(fields[i] for i in id_cols) if len(fields) > max(id_cols, default=-1) \
                else None
            bad.append((key, MeasuredDataError(
                path, lineno, None, f"found {len(fields)} fields, expected {len(names)} "
                f"({', '.join(names)}){hint}")))
            continue
        key = tuple(fields[i] for i in id_cols)
        groups.setdefault(key, []).append((lineno, ",".join(fields[i] for i in kept)))
    entries, errors = [], dict()
    for key, err in bad:
        errors.setdefault(key, err)  # the first bad row of a measurement names it
    keys = list(dict.fromkeys([*groups, *errors]))
    for key in keys:
        entry_ids = {**base_ids, **({names[i]: v for i, v in zip(id_cols, key)}
                                    if key is not None else {})}
        if key in errors:
            entries.append(StudyEntry(entry_ids, None, str(errors[key]), str(path)))
            continue
        rows = groups[key]
        numbers = [n for n, _ in comments] + [header[0]] + [n for n, _ in rows]
        body = [c for _, c in comments] + [sub_header] + [r for _, r in rows]
        try:
            data = _load_text(path, "\n".join(body), numbers, available_probes,
                              pressure_range_mbar, range_note, metadata=entry_ids)
        except MeasuredDataError as err:
            entries.append(StudyEntry(entry_ids, None, str(err), str(path)))
            continue
        entries.append(StudyEntry(entry_ids, data, None, str(path)))
    if not entries:
        entries.append(StudyEntry(base_ids, None, str(MeasuredDataError(
            path, len(lines), None, "no data rows after the header")), str(path)))
    return entries
