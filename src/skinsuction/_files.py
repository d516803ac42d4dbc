"""Results files written atomically: a reader never sees a partial file.

What is written (strict JSON, tables, text) is :mod:`skinsuction.results`.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
from pathlib import Path

__all__ = ["atomic_output", "write_table", "file_sha256"]


@contextlib.contextmanager
def atomic_output(path):
    """Yield a temporary path next to ``path``; move it to ``path`` on success.

    On an exception the temporary file is removed and ``path`` is left as it was,
    so a reader never sees a partially written file.

    Examples
    --------
    >>> import tempfile
    >>> target = Path(tempfile.mkdtemp()) / "t.txt"
    >>> with atomic_output(target) as tmp:
    ...     _ = tmp.write_text("done")
    >>> target.read_text()
    'done'
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp{path.suffix}")
    # a writer killed before its move (SIGKILL, power cut) leaves its temporary file:
    # the next writer of the same output removes it (one job writes an output)
    for stale in path.parent.glob(f".{path.name}.*.tmp{path.suffix}"):
        if stale != tmp:
            with contextlib.suppress(FileNotFoundError):
                stale.unlink()
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()


def write_table(frame, path, **to_csv) -> Path:
    """Write a results table as CSV, atomically.

    Public as :func:`skinsuction.results.write_table`.

    Parameters
    ----------
    frame : pandas.DataFrame
        The table; its index is not written.
    path : path-like
        The CSV file; its folder is created.
    **to_csv
        More options of :meth:`pandas.DataFrame.to_csv` (``float_format`` ...).

    Returns
    -------
    Path
        ``path``.
    """
    with atomic_output(path) as tmp:
        frame.to_csv(tmp, index=False, **to_csv)
    return Path(path)


def file_sha256(path) -> str:
    """SHA-256 of a file's bytes (hex), read in 1 MB blocks."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()
