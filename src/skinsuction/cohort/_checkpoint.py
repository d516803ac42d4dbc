"""A study's rows kept as they finish, so that a run cut short loses no measurement.

A study of hundreds of subjects runs for minutes to hours; before this file a run
killed at 90 % (a time limit, a reboot) kept nothing.  Each finished row is
appended to ``rows.partial.jsonl`` in the output folder (one JSON line, flushed
to disk); a rerun with the same settings, space and files reads them back and
analyses only the rest.  The file is removed once the study's files are written.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from pathlib import Path

__all__ = ["Checkpoint", "CHECKPOINT_FILE"]

CHECKPOINT_FILE = "rows.partial.jsonl"


def _plain(value):
    """JSON for NumPy scalars and NaN (as null: a row's missing value)."""
    if hasattr(value, "item"):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None if math.isnan(value) else value
    return value


class Checkpoint:
    """The rows a study has finished, on disk.

    Parameters
    ----------
    path : path-like
        The file (``<out>/rows.partial.jsonl``).
    fingerprint : dict
        What the rows depend on beyond their own file (space, settings, seed,
        version): rows written under another fingerprint are not reused.
    resume : bool
        Read back the rows of an earlier run with the same fingerprint.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "rows.partial.jsonl"
    >>> with Checkpoint(path, {"seed": 0}) as c:
    ...     c.add({"row": 0, "source": "a.csv", "sha256": "ab", "seed": 0, "x1d_mpa": 0.02})
    >>> again = Checkpoint(path, {"seed": 0})
    >>> again.finished(0, "a.csv", "ab", 0)["x1d_mpa"], again.finished(1, "b.csv", "cd", 1)
    (0.02, None)
    >>> other = Checkpoint(path, {"seed": 1})  # other settings: set aside, not reused
    >>> other.resumed, other.stale.name
    (0, 'rows.partial.jsonl.stale')
    """

    def __init__(self, path, fingerprint: dict, resume: bool = True):
        self.path = Path(path)
        self.key = hashlib.sha256(json.dumps(fingerprint, sort_keys=True,
                                             default=str).encode()).hexdigest()
        self.stale = None
        if not resume and self.path.is_file():
            self._set_aside()
        self._rows = self._read()
        self.resumed = len(self._rows)
        self._file = None

    def _read(self) -> dict:
        if not self.path.is_file():
            return {}
        lines = self.path.read_text(encoding="utf-8").splitlines()
        try:
            head = json.loads(lines[0]) if lines else {}
        except json.JSONDecodeError:
            head = {}
        if head.get("fingerprint") != self.key:
            # another run's rows (other settings, space or version): kept, not reused
            self._set_aside()
            return {}
        rows = {}
        for line in lines[1:]:
            try:
                row = json.loads(line)
            except json.JSONDecodeError:
                continue  # the line being written when the run was cut
            rows[(row["row"], row["source"], row["sha256"], row["seed"])] = row
        return rows

    def _set_aside(self) -> None:
        self.stale = self.path.with_name(self.path.name + ".stale")
        os.replace(self.path, self.stale)

    def finished(self, index, source, sha256, seed) -> dict | None:
        """The row of this measurement from an earlier run, or None."""
        return self._rows.get((index, str(source), sha256, seed))

    def add(self, row: dict) -> None:
        """Append a finished row (flushed to disk before returning)."""
        if self._file is None:
            fresh = not self.path.is_file() or not self._rows
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._file = open(self.path, "w" if fresh else "a", encoding="utf-8")
            if fresh:
                self._file.write(json.dumps({"fingerprint": self.key}) + "\n")
        self._file.write(json.dumps({k: _plain(v) for k, v in row.items()}) + "\n")
        self._file.flush()
        os.fsync(self._file.fileno())

    def close(self) -> None:
        if self._file is not None:
            self._file.close()
            self._file = None

    def remove(self) -> None:
        """Delete the file: the study's own files now hold every row."""
        self.close()
        self.path.unlink(missing_ok=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
