"""The measured curves as loaded, their error, and the limits of a file."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

REQUIRED_COLUMNS = ("probe_mm", "pressure_mbar", "deflection_mm")

OPTIONAL_COLUMNS = ("curve",)

#: Points per curve and rows per file: beyond them a file is refused before it
#: fills the memory (a Cutometer curve has tens to hundreds of points).
MAX_POINTS_PER_CURVE = 2_000

MAX_ROWS_PER_FILE = 2_000_000

MAX_FILE_BYTES = 256 * 2 ** 20


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

    def __reduce__(self):
        # rebuilt from its fields, so that it crosses a process pool (study workers)
        return type(self), (self.path, self.line, self.column, self.reason)


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
    lines : tuple of int
        The file's line of each point (empty for curves built in memory), so that a
        check of loaded data against a space names the line as the loader does.
    """

    probe_mm: float
    pressure_mbar: np.ndarray
    deflection_mm: np.ndarray
    curve: str = ""
    first_line: int = 0
    lines: tuple = ()

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


@dataclass
class _Rows:
    probe: float
    curve: str
    lines: list = field(default_factory=list)
    pressure: list = field(default_factory=list)
    deflection: list = field(default_factory=list)
