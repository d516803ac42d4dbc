"""Reading measured CSV files and long study tables (format: :mod:`skinsuction.measured`)."""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass

import numpy as np

from ._checks import _check_curve, _check_space, _label
from ._geometry import check_geometry_metadata
from ._types import (
    MAX_FILE_BYTES,
    MAX_POINTS_PER_CURVE,
    MAX_ROWS_PER_FILE,
    OPTIONAL_COLUMNS,
    REQUIRED_COLUMNS,
    MeasuredCurve,
    MeasuredData,
    MeasuredDataError,
    _Rows,
    _show,
)

__all__ = ["load_measured", "check_against_space", "StudyEntry", "load_table"]


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


def _header(path, lineno: int, text: str, extra_columns: bool = False, *,
            required=REQUIRED_COLUMNS, optional=OPTIONAL_COLUMNS, hints=None) -> list[str]:
    """The column names of a header line, checked against ``required`` and ``optional``
    (the time-curve loader passes its own columns and unit hints)."""
    hints = {**_UNIT_HINTS, **(hints or {})}
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
        if name not in tuple(required) + tuple(optional) and not (
                extra_columns and name.lower() not in hints):
            hint = hints.get(name.lower())
            if hint is None:
                hint = (
                    "unexpected column; the columns are "
                    + ", ".join(required)
                    + " and optionally "
                    + ", ".join(optional)
                )
            raise MeasuredDataError(path, lineno, name, hint)
    for name in required:
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


def _lines(text: str):
    """The lines of a text: LF, CRLF or CR-only (old Mac) line ends."""
    return text.replace("\r\n", "\n").replace("\r", "\n").split("\n")


def _comment(stripped: str, lineno: int, comments: list, metadata: dict, meta_lines: dict):
    """Keep a ``#`` line: every comment, and ``key: value`` ones as metadata (a later key
    overrides an earlier one; its line is kept for located errors)."""
    comment = stripped[1:].strip()
    comments.append(comment)
    key, sep, value = comment.partition(":")
    if sep and key.strip():
        metadata[key.strip()] = value.strip()
        meta_lines[key.strip()] = lineno


def _parse(path, text: str, line_numbers=None):
    comments, metadata, header, groups = [], {}, None, {}
    meta_lines = {}
    lines = _lines(text)
    numbers = range(1, len(lines) + 1) if line_numbers is None else line_numbers
    for lineno, line in zip(numbers, lines):
        line = line.rstrip("\r")
        stripped = line.strip()
        if not stripped:
            continue
        if stripped.startswith("#"):
            _comment(stripped, lineno, comments, metadata, meta_lines)
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
    return header, groups, comments, metadata, meta_lines


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
    _, groups, comments, file_metadata, meta_lines = _parse(path, text, line_numbers)
    metadata = {**file_metadata, **(metadata or {})}
    # the layer thicknesses: a header line names its line; a study column its first row
    first_row = min(r.lines[0] for r in groups.values())
    lines = {k: meta_lines.get(k, first_row) if k in (metadata or {}) and k not in file_metadata
             else meta_lines.get(k) for k in metadata}
    check_geometry_metadata(path, metadata, lines)
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
            lines=tuple(rows.lines),
        )
        for rows in groups.values()
    )
    return MeasuredData(str(path), curves, metadata, tuple(comments), tuple(warnings))


def check_against_space(data: MeasuredData, *, available_probes=None, pressure_range_mbar=None,
                        range_note: str | None = None) -> MeasuredData:
    """Check loaded curves against a simulated space, as :func:`load_measured` does.

    A caller that learns the space's probes or reach only after reading the file
    (the reach depends on the layers the file gives) checks the loaded data
    instead of reading the file again; the message names the same line and column.

    Parameters
    ----------
    data : MeasuredData
        As loaded (its curves know the line of each point).
    available_probes : iterable of float, optional
        Probe diameters (mm) held by the space; other probes are rejected.
    pressure_range_mbar : (float, float), optional
        Pressure range of the space; pressures outside are rejected.
    range_note : str, optional
        What sets that range, for the error.

    Returns
    -------
    MeasuredData
        ``data`` itself.

    Raises
    ------
    MeasuredDataError
        For the first curve outside the space, naming the file, line and column.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "m.csv"
    >>> _ = path.write_text("probe_mm,pressure_mbar,deflection_mm\\n6,0,0\\n6,150,0.8\\n")
    >>> check_against_space(load_measured(path), pressure_range_mbar=(0, 100))
    Traceback (most recent call last):
    ...
    skinsuction.measured.MeasuredDataError: ...m.csv, line 3, column 'pressure_mbar': pressure 150 mbar is outside the simulated range 0..100 mbar
    """
    for c in data.curves:
        lines = list(c.lines) if len(c.lines) == len(c) else [c.first_line or None] * len(c)
        rows = _Rows(c.probe_mm, c.curve, lines, list(c.pressure_mbar), list(c.deflection_mm))
        _check_space(data.path, rows, available_probes, pressure_range_mbar, range_note)
    return data


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
    return _table_entries(path, text, ids, available_probes, pressure_range_mbar, range_note)


def _table_entries(path, text, ids=None, available_probes=None, pressure_range_mbar=None,
                   range_note=None) -> list:
    """The entries of :func:`load_table` from the text of the file, already read."""
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
