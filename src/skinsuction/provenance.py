"""Provenance of results: package versions, git commit, configuration, source hashes.

Every database and table written by the study carries a JSON-able provenance
record so that a result file can be traced back to the code and the settings that
produced it, without the workflow's own bookkeeping.

Examples
--------
>>> from skinsuction.provenance import collect
>>> record = collect(config={"mesh": {"refinement": 1.0}})
>>> {"config", "created_utc", "git", "versions"} <= set(record)
True
>>> "felupe" in record["versions"]
True
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import hashlib
import logging
import platform
import subprocess
import sys
from importlib import metadata
from pathlib import Path

#: Distributions whose versions are recorded in every provenance record.
PACKAGES = (
    "skinsuction",
    "felupe",
    "numpy",
    "scipy",
    "pandas",
    "pyarrow",
    "matplotlib",
    "snakemake",
)

#: Root of the package sources (``src/skinsuction``).
PACKAGE_DIR = Path(__file__).resolve().parent


def versions(packages=PACKAGES) -> dict:
    """Installed versions of ``packages`` and of Python.

    A distribution that is not installed is reported as ``None``; for
    ``skinsuction`` run from a source tree without installation the version in
    ``skinsuction.__version__`` is used.

    Examples
    --------
    >>> v = versions(("numpy",))
    >>> sorted(v)
    ['numpy', 'python']
    """
    out = {"python": platform.python_version()}
    for name in packages:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = None
    if out.get("skinsuction") is None and "skinsuction" in packages:
        import skinsuction

        out["skinsuction"] = getattr(skinsuction, "__version__", None)
    return out


def _git(args, cwd) -> str | None:
    try:
        res = subprocess.run(
            ["git", *args],
            cwd=cwd,
            capture_output=True,
            text=True,
            timeout=20,
            check=False,
        )
    except (OSError, subprocess.SubprocessError):
        return None
    return res.stdout.strip() if res.returncode == 0 else None


def git_info(path=None) -> dict:
    """Commit and dirty flag of the git work tree containing ``path``.

    ``path`` defaults to the package sources, then the current directory. Files
    ignored by git (``results/``) and untracked files do not make the tree dirty.

    Returns
    -------
    dict
        ``{"commit": str | None, "dirty": bool | None, "root": str | None}``;
        all ``None`` outside a git work tree or without a ``git`` executable.
    """
    candidates = [Path(path)] if path is not None else [PACKAGE_DIR, Path.cwd()]
    for cand in candidates:
        cand = cand if cand.is_dir() else cand.parent
        commit = _git(["rev-parse", "HEAD"], cand)
        if commit:
            status = _git(["status", "--porcelain", "--untracked-files=no"], cand)
            root = _git(["rev-parse", "--show-toplevel"], cand)
            return {
                "commit": commit,
                "dirty": None if status is None else bool(status),
                "root": root,
            }
    return {"commit": None, "dirty": None, "root": None}


def source_hash(*parts, root=PACKAGE_DIR, length=16) -> str:
    """Hash of the package sources under ``root`` named by ``parts``.

    A part is a file or a folder (all files below it, ``__pycache__`` and
    compiled files excluded), relative to ``src/skinsuction``. The hash covers
    relative file names and contents, so renaming, adding or editing a file
    changes it. The workflow passes it as a rule parameter, so that a change of
    the code a rule depends on reruns that rule (Snakemake does not track
    imported modules).

    Examples
    --------
    >>> h = source_hash("space")
    >>> len(h)
    16
    >>> h == source_hash("space")
    True
    """
    root = Path(root)
    digest = hashlib.sha256()
    for part in parts:
        target = root / part
        if target.is_dir():
            files = sorted(
                p
                for p in target.rglob("*")
                if p.is_file()
                and "__pycache__" not in p.parts
                and p.suffix not in {".pyc", ".pyo"}
            )
        elif target.is_file():
            files = [target]
        else:
            raise FileNotFoundError(f"no source file or folder {target}")
        for f in files:
            digest.update(f.relative_to(root).as_posix().encode())
            digest.update(b"\0")
            digest.update(f.read_bytes())
            digest.update(b"\0")
    return digest.hexdigest()[:length]


def jsonable(obj):
    """``obj`` converted to plain JSON types (NumPy scalars/arrays, paths, sets).

    :func:`skinsuction.results.jsonable` as the provenance records have always
    used it: an object of no JSON type becomes its ``str``, and NaN stays NaN (the
    records go into Parquet metadata that Python's :mod:`json` reads back; the
    result files are strict, see :mod:`skinsuction.results`).

    Parameters
    ----------
    obj : object
        The record.

    Returns
    -------
    object
        Dicts with string keys, lists, str, int, float, bool and None.

    Examples
    --------
    >>> import numpy as np
    >>> jsonable({"a": np.float32(0.5), "b": (1, 2), "c": object}) == {
    ...     "a": 0.5, "b": [1, 2], "c": "<class 'object'>"}
    True
    """
    from skinsuction.results import jsonable as _jsonable

    return _jsonable(obj, strict=False, default=str)


def collect(config=None, **extra) -> dict:
    """A provenance record: creation time, versions, git state, configuration.

    Parameters
    ----------
    config : mapping, optional
        The (validated) study configuration used; stored as given.
    **extra
        More JSON-able entries (e.g. ``space="paper"``, ``source_hash=...``).

    Returns
    -------
    dict
        JSON-able; ``json.dumps`` works on it.
    """
    record = {
        "created_utc": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "platform": platform.platform(),
        "executable": sys.executable,
        "package_dir": str(PACKAGE_DIR),
        "versions": versions(),
        "git": git_info(),
        "config": config,
    }
    record.update(extra)
    return jsonable(record)


@contextlib.contextmanager
def log_to_file(path, level=logging.INFO):
    """Send ``logging``, ``print`` and warnings output to the file ``path``.

    Used by the workflow scripts to honour a rule's ``log:`` file.

    Examples
    --------
    >>> import tempfile, os
    >>> p = os.path.join(tempfile.mkdtemp(), "a.log")
    >>> with log_to_file(p):
    ...     logging.getLogger("skinsuction").info("hello")
    >>> "hello" in open(p).read()
    True
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", buffering=1) as stream:
        handler = logging.StreamHandler(stream)
        handler.setFormatter(
            logging.Formatter("%(asctime)s %(levelname)s %(name)s: %(message)s")
        )
        root = logging.getLogger()
        old_level = root.level
        root.addHandler(handler)
        root.setLevel(level)
        logging.captureWarnings(True)
        try:
            with contextlib.redirect_stdout(stream), contextlib.redirect_stderr(stream):
                yield stream
        except BaseException:
            logging.getLogger("skinsuction").exception("failed")
            raise
        finally:
            logging.captureWarnings(False)
            root.removeHandler(handler)
            root.setLevel(old_level)
