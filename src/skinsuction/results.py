"""Result files, written one way: strict JSON, Markdown tables, CSV tables, text.

Every result of skinsuction (``report.json``, ``identification.json``,
``study.json``, ``summary.md``, ``comparison.csv`` ...) goes through this module,
so there is one answer to "what becomes of a NaN, a NumPy number, a path":

* :func:`jsonable` turns a result into plain JSON types: NumPy scalars and arrays
  become Python numbers and lists, NaN and infinities become ``None`` (strict JSON
  has neither), paths become strings, tuples and sets lists, objects with
  ``to_json()`` or ``to_dict()`` (and dataclasses) their dict;
* :func:`dumps` is :func:`json.dumps` of that, refusing anything else
  (``allow_nan=False``: a non-finite number that slipped through is an error, not
  an unreadable file);
* :func:`write_json`, :func:`write_text` and :func:`write_table` (CSV) write a
  file atomically (:func:`skinsuction._files.atomic_output`): a reader never sees
  half of it;
* :func:`markdown_table` is the one Markdown table writer.

The module is in the lowest layer (it imports only the standard library and
``skinsuction._files``; NumPy and pandas only when given their objects), so any
layer may use it, the workflow's preamble included.

Examples
--------
>>> import numpy as np
>>> jsonable({"x": np.float64(0.5), "n": np.int64(3), "bad": float("nan"),
...           "a": np.array([1.0, np.inf]), 6.0: (1, 2)})
{'x': 0.5, 'n': 3, 'bad': None, 'a': [1.0, None], '6.0': [1, 2]}
>>> dumps({"E_um": np.float32(0.25), "cause": "none"})
'{"E_um": 0.25, "cause": "none"}'
>>> print(markdown_table([{"group": "treated", "n": 15, "p": 6.1e-05, "x": None}],
...                      digits=3, align=False))
| group | n | p | x |
|---|---|---|---|
| treated | 15 | 6.1e-05 |  |
"""

from __future__ import annotations

import dataclasses
import json
import math
import sys
from pathlib import Path, PurePath

from skinsuction._files import atomic_output, write_table

__all__ = ["jsonable", "dumps", "write_json", "write_text", "markdown_table", "write_table"]


def _numpy():
    """NumPy if it is loaded (no NumPy object can exist otherwise), else None."""
    return sys.modules.get("numpy")


def _key(k, strict: bool) -> str:
    """A mapping key as :func:`json.dumps` writes it (other keys: their ``str``)."""
    np = _numpy()
    if np is not None and isinstance(k, np.generic):
        k = k.item()
    if isinstance(k, str):
        return k
    if k is True or k is False or k is None:
        return json.dumps(k)
    if isinstance(k, (int, float)):
        return json.dumps(k, allow_nan=not strict)
    return str(k)


def jsonable(obj, *, strict: bool = True, default=None):
    """``obj`` as plain JSON types, recursively.

    Parameters
    ----------
    obj : object
        A result: dicts (and other mappings: objects with ``items()``), lists,
        tuples, sets, numbers, strings, None, NumPy scalars and arrays, paths,
        objects with ``to_json()`` or ``to_dict()`` returning a dict, dataclasses.
    strict : bool
        True (the default): NaN and infinities become ``None``, as strict JSON
        has neither.  False: they stay floats (for metadata read back by Python's
        :mod:`json`, which accepts them; :mod:`skinsuction.provenance` only).
    default : callable, optional
        Called on an object of no type above (before its ``to_json``, ``to_dict``
        or dataclass fields are tried); its result is converted in turn.  Without
        it such an object raises TypeError.

    Returns
    -------
    object
        Dicts with string keys (as :func:`json.dumps` writes keys), lists, str,
        int, float, bool and None only.

    Raises
    ------
    TypeError
        An object that none of the rules converts (without ``default``).

    Examples
    --------
    >>> from pathlib import Path
    >>> jsonable({"path": Path("a") / "b", "ids": {3}, "inf": float("inf")})
    {'path': 'a/b', 'ids': [3], 'inf': None}
    >>> jsonable([float("nan")], strict=False)
    [nan]
    >>> jsonable(object(), default=lambda o: "an object")
    'an object'
    """
    def convert(o):
        if o is None or isinstance(o, (str, bool)):
            return str(o) if isinstance(o, str) and type(o) is not str else o
        if isinstance(o, int):
            return int(o)
        if isinstance(o, float):
            x = float(o)
            return x if not strict or math.isfinite(x) else None
        if isinstance(o, dict):
            return {_key(k, strict): convert(v) for k, v in o.items()}
        if isinstance(o, (list, tuple, set, frozenset)):
            return [convert(v) for v in o]
        np = _numpy()
        if np is not None:
            if isinstance(o, np.generic):
                return convert(o.item())
            if isinstance(o, np.ndarray):
                return convert(o.tolist())
        if isinstance(o, PurePath):
            return str(o)
        if callable(getattr(o, "items", None)):
            return convert(dict(o.items()))
        if default is not None:
            return convert(default(o))
        for method in ("to_json", "to_dict"):
            value = getattr(o, method, None)
            if callable(value):
                out = value()
                if isinstance(out, dict):
                    return convert(out)
        if dataclasses.is_dataclass(o) and not isinstance(o, type):
            return convert(dataclasses.asdict(o))
        raise TypeError(f"{type(o).__name__} is not JSON serialisable: {o!r:.80}")

    return convert(obj)


def dumps(obj, *, indent=None, ensure_ascii: bool = True, sort_keys: bool = False,
          default=None) -> str:
    """Strict JSON text of a result: :func:`jsonable`, then :func:`json.dumps`.

    Parameters
    ----------
    obj : object
        Anything :func:`jsonable` converts.
    indent : int or None
        Indentation of :func:`json.dumps` (None: one line).
    ensure_ascii : bool
        Escape non-ASCII characters (``µm`` as ``\\u00b5m``) as :func:`json.dumps` does.
    sort_keys : bool
        Sort the keys of every dict.
    default : callable, optional
        For objects :func:`jsonable` does not know (e.g. ``str``).

    Returns
    -------
    str
        JSON without NaN or infinities (``allow_nan=False``), no trailing newline.

    Examples
    --------
    >>> print(dumps({"a": [1, float("-inf")]}, indent=1))
    {
     "a": [
      1,
      null
     ]
    }
    """
    return json.dumps(jsonable(obj, default=default), indent=indent, ensure_ascii=ensure_ascii,
                      sort_keys=sort_keys, allow_nan=False)


def write_text(path, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically.

    Parameters
    ----------
    path : path-like
        The file; its folder is created.
    text : str
        The whole content.

    Returns
    -------
    Path
        ``path``.
    """
    with atomic_output(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(path)


def write_json(path, obj, *, indent=1, ensure_ascii: bool = False, sort_keys: bool = False,
               default=None) -> Path:
    """Write a result as strict JSON (:func:`dumps`, then a newline), atomically.

    Parameters
    ----------
    path : path-like
        The file; its folder is created.
    obj : object
        Anything :func:`jsonable` converts.
    indent, ensure_ascii, sort_keys, default :
        As for :func:`dumps` (but ``ensure_ascii`` is False by default: the file is
        UTF-8, ``µm`` stays ``µm``).

    Returns
    -------
    Path
        ``path``.

    Examples
    --------
    >>> import tempfile
    >>> p = write_json(Path(tempfile.mkdtemp()) / "r.json", {"noise_um": float("nan")})
    >>> p.read_text()
    '{\\n "noise_um": null\\n}\\n'
    """
    return write_text(path, dumps(obj, indent=indent, ensure_ascii=ensure_ascii,
                                  sort_keys=sort_keys, default=default) + "\n")


def _missing(v) -> bool:
    return v is None or (isinstance(v, float) and math.isnan(v))


def _cell(v, digits: int) -> str:
    if _missing(v):
        return ""
    if isinstance(v, float):
        return f"{v:.{digits}g}"
    return str(v)


def markdown_table(table, columns=None, *, digits: int = 4, align: bool = True) -> str:
    """A GitHub Markdown table of a frame or of rows.

    Parameters
    ----------
    table : pandas.DataFrame or sequence of dict or sequence of sequence
        The rows.  A frame's rows are read as :meth:`pandas.DataFrame.iterrows`
        gives them (a row of numbers only is a row of floats); a dict row gives
        the value of each column (none: an empty cell), a sequence its cells in
        the order of ``columns``.
    columns : sequence of str, optional
        The columns, in order (default: the frame's, or the first row's keys).
    digits : int
        Significant digits of a float (``format(x, f".{digits}g")``); other values
        are written with ``str``.  None and NaN are empty cells.
    align : bool
        True: numeric columns right-aligned (``---:``), others left (``:---``);
        False: plain ``---`` (the renderer's default).

    Returns
    -------
    str
        Header, separator and one line per row, without a trailing newline.

    Examples
    --------
    >>> import pandas as pd
    >>> print(markdown_table(pd.DataFrame({"a": [1.0, 2.5], "b": ["x", "y"]})))
    | a | b |
    |---:|:---|
    | 1 | x |
    | 2.5 | y |
    """
    if hasattr(table, "iterrows"):
        import pandas as pd

        cols = list(table.columns) if columns is None else list(columns)
        numeric = [pd.api.types.is_numeric_dtype(table[c]) for c in cols]
        cells = [[row.get(c) for c in cols] for _, row in table.iterrows()]
    else:
        rows = list(table)
        cols = list(columns) if columns is not None else list(rows[0]) if rows else []
        cells = [[row.get(c) for c in cols] if hasattr(row, "get") else list(row)
                 for row in rows]
        numeric = [all(isinstance(v, (int, float)) and not isinstance(v, bool)
                       for v in column if not _missing(v)) for column in zip(*cells)]
        numeric += [False] * (len(cols) - len(numeric))
    lines = ["| " + " | ".join(str(c) for c in cols) + " |",
             "|" + "|".join(("---:" if n else ":---") if align else "---" for n in numeric)
             + "|"]
    for row in cells:
        lines.append("| " + " | ".join(_cell(v, digits) for v in row) + " |")
    return "\n".join(lines)
