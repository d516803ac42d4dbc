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

import math

import pandas as pd

from skinsuction._files import atomic_output


def _cell(x, digits: int = 4) -> str:
    if isinstance(x, float):
        if math.isnan(x):
            return ""
        return f"{x:.{digits}g}"
    return str(x)


def markdown_table(frame: pd.DataFrame, digits: int = 4) -> str:
    """A GitHub Markdown table; numbers right-aligned, ``digits`` significant digits."""
    cols = list(frame.columns)
    num = [pd.api.types.is_numeric_dtype(frame[c]) for c in cols]
    lines = ["| " + " | ".join(cols) + " |",
             "|" + "|".join("---:" if n else ":---" for n in num) + "|"]
    for _, row in frame.iterrows():
        lines.append("| " + " | ".join(_cell(row[c], digits) for c in cols) + " |")
    return "\n".join(lines)


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


