"""Tables of the identification study: timing and optimiser comparison (CSV + Markdown).

Examples
--------
>>> import pandas as pd
>>> print(markdown_table(pd.DataFrame({"a": [1.0, 2.5], "b": ["x", "y"]})))
| a | b |
|---:|:---|
| 1 | x |
| 2.5 | y |
"""

from __future__ import annotations

import pandas as pd

from skinsuction._files import atomic_output
from skinsuction.results import markdown_table as _markdown_table


def markdown_table(frame: pd.DataFrame, digits: int = 4) -> str:
    """A GitHub Markdown table; numbers right-aligned, ``digits`` significant digits.

    :func:`skinsuction.results.markdown_table` of a frame (the one table writer).

    Parameters
    ----------
    frame : pandas.DataFrame
        The table.
    digits : int
        Significant digits of a float; None and NaN are empty cells.

    Returns
    -------
    str
        The table, without a trailing newline.
    """
    return _markdown_table(frame, digits=digits)


def write_markdown(path, title: str, sections) -> None:
    """Write ``# title`` then each ``(text, frame)`` section (frame may be None)."""
    parts = [f"# {title}", ""]
    for text, frame in sections:
        if text:
            parts += [text, ""]
        if frame is not None:
            parts += [markdown_table(frame), ""]
    with atomic_output(path) as tmp:
        tmp.write_text("\n".join(parts), encoding="utf-8")


