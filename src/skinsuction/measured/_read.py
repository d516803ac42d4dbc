"""One measured file, whatever its kind: read once, the kind decided in one place.

A measured file is a pressure ramp M(p) (:func:`load_measured`, a study table of
them :func:`load_table`) or Cutometer time curves (:func:`load_time_curves`); the
header tells them apart (a ``time_s`` column).  :func:`read_measurement` reads the
file once and hands back what the matching loader gives, so a command, a study
or a library call does not look at the file twice to decide what it is.
"""

from __future__ import annotations

import os

from ._load import _load_text, _read_text, _table_entries
from ._timecurve import _has_time_column, _load

__all__ = ["read_measurement"]


def read_measurement(path: str | os.PathLike, *, table: bool = False, ids: dict | None = None,
                     available_probes=None, pressure_range_mbar=None,
                     range_note: str | None = None):
    """Read a measured file once: a pressure ramp or time curves, by its header.

    Parameters
    ----------
    path : str or path-like
        A measured CSV (format: :mod:`skinsuction.measured`).
    table : bool
        Read a pressure-ramp file as a study table (extra columns are ids): one
        :class:`StudyEntry` per measurement, a bad one carrying its error, as
        :func:`load_table` does.  Time curves are read as one file either way.
    ids : dict, optional
        With ``table``: ids of the whole file (e.g. from a manifest).
    available_probes, pressure_range_mbar, range_note
        Pressure ramps only: the checks against a simulated space of
        :func:`load_measured` (see :func:`check_against_space` to check later).

    Returns
    -------
    MeasuredData or MeasuredTimeData or list of StudyEntry
        What :func:`load_measured` (or :func:`load_table` with ``table``) gives for
        a pressure ramp, what :func:`load_time_curves` gives for time curves.

    Raises
    ------
    MeasuredDataError
        The file cannot be read, or (not for a ramp table's measurements) any
        problem of it, with file, line and column in the message.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "s01.csv"
    >>> _ = path.write_text("probe_mm,pressure_mbar,deflection_mm\\n6,0,0\\n6,50,0.4\\n")
    >>> type(read_measurement(path)).__name__
    'MeasuredData'
    >>> [e.error is None for e in read_measurement(path, table=True, ids={"subject": "S01"})]
    [True]
    """
    text = _read_text(path)
    if _has_time_column(text):
        return _load(path, text)
    if table:
        return _table_entries(path, text, ids, available_probes, pressure_range_mbar,
                              range_note)
    return _load_text(path, text, None, available_probes, pressure_range_mbar, range_note)
