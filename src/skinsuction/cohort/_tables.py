"""The tables of a study: its rows as one frame, the summary, the files written.

:func:`study_frame` makes the rows of :func:`skinsuction.cohort.study_rows` one
frame of plain Arrow types; :func:`summary_markdown` writes ``summary.md``;
:func:`write_study_files` writes ``curves.parquet``, ``comparison.csv``,
``summary.md`` and ``study.json`` (each atomically, through
:mod:`skinsuction.results`).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from skinsuction.results import dumps, markdown_table, write_json, write_table, write_text

from ._rows import RESULT_COLUMNS

__all__ = ["study_frame", "summary_markdown", "space_text", "write_study_files"]

#: The columns of the group comparison in ``summary.md``.
COMPARISON_COLUMNS = ("group", "comparison", "test", "n", "median_change_percent",
                      "ci_low_percent", "ci_high_percent", "p_value", "effect_size")


def study_frame(rows):
    """The rows of a study as one frame: ids first, then :data:`RESULT_COLUMNS`.

    Parameters
    ----------
    rows : list of dict
        As :func:`skinsuction.cohort.study_rows` gives them.

    Returns
    -------
    tuple
        ``(frame, id_columns)``: a column of numbers (or none) is float64, of text
        string, an open-interval flag or ``systematic_misfit`` boolean (nullable).
    """
    import pandas as pd

    df = pd.DataFrame(rows)
    for c in RESULT_COLUMNS:
        if c not in df.columns:
            df[c] = None
    id_cols = [c for c in df.columns if c not in RESULT_COLUMNS]
    df = df[id_cols + list(RESULT_COLUMNS)]
    for c in ("x1d_lower_open", "x1d_upper_open", "x1h_lower_open", "x1h_upper_open",
              "systematic_misfit"):
        df[c] = df[c].astype("boolean")
    for c in RESULT_COLUMNS:
        if df[c].dtype == object and c not in ("systematic_misfit",):
            vals = [v for v in df[c] if v is not None and not (isinstance(v, float)
                                                                and math.isnan(v))]
            if vals and all(isinstance(v, (int, float, np.number)) and not isinstance(v, bool)
                            for v in vals):
                df[c] = df[c].astype("float64")
            elif not vals or all(isinstance(v, str) for v in vals):
                df[c] = df[c].astype("string")
    return df, id_cols


def space_text(meta, markdown: bool = True) -> str:
    """The study's space, in words: its description, and its path unless given.

    Parameters
    ----------
    meta : dict
        The study's record (``space``, ``space_description``, ``space_source``).
    markdown : bool
        Put the path in backquotes.

    Returns
    -------
    str
    """
    desc = meta.get("space_description")
    if not desc:
        return str(meta["space"])
    q = "`" if markdown else ""
    return desc if meta.get("space_source") == "given" else f"{desc} ({q}{meta['space']}{q})"


# ------------------------------------------------------------------ summary.md
def _group_lines(df) -> list:
    """X1d per group (and visit): median, IQR, median interval width."""
    keys = ["group"] + (["visit"] if "visit" in df.columns else [])
    rows = []
    for key, g in df[df["x1d_mpa"].notna()].groupby(keys):
        key = key if isinstance(key, tuple) else (key,)
        x = g["x1d_mpa"].astype(float)
        w = ((g["x1d_upper_mpa"] - g["x1d_lower_mpa"]) / g["x1d_mpa"]).astype(float)
        rows.append([f"{key[0]}", f"{key[1] if len(key) > 1 else ''}", f"{len(g)}",
                     f"{x.median():.4g}", f"{x.quantile(0.25):.3g}-{x.quantile(0.75):.3g}",
                     f"{100 * w.median():.2g} %"])
    columns = ["group", "visit", "n", "median X1d (MPa)", "IQR (MPa)",
               "median interval width"]
    return ["## X1d per group", "", markdown_table(rows, columns, align=False), ""]


def _cause_lines(df) -> list:
    """How often each cause was named, per group."""
    key = "group" if "group" in df.columns else None
    tab = (df.groupby(key)["cause"].value_counts().unstack(fill_value=0) if key
           else df["cause"].value_counts().to_frame().T)
    rows = [[f"{idx}", *(str(int(v)) for v in r)] for idx, r in tab.iterrows()]
    return ["## Named causes (diagnosis)", "",
            markdown_table(rows, [key or "", *tab.columns], align=False), ""]


def _error_lines(errors, id_cols) -> list:
    lines = ["## Errors", ""]
    for _, r in errors.iterrows():
        ids = ", ".join(f"{c}={r[c]}" for c in id_cols if r[c] is not None
                        and str(r[c]) not in ("", "<NA>", "nan"))
        lines.append(f"- {ids}: {r['error']}")
    return lines + [""]


def summary_markdown(df, id_cols, comparison, notes, meta) -> str:
    """``summary.md``: the counts, X1d per group, the group comparison, the causes.

    Parameters
    ----------
    df : pandas.DataFrame
        The study's frame (:func:`study_frame`).
    id_cols : list of str
        Its id columns.
    comparison : list of dict
        The group comparison (:func:`skinsuction.cohort.compare_groups`).
    notes : list of str
        What the comparison left out and why.
    meta : dict
        The study's record (name, path, space, settings, seconds, date, version).

    Returns
    -------
    str
        Markdown, ending with a newline.
    """
    n, errors = len(df), df[df["error"].notna()]
    lines = [f"# Study {meta['name']}", "",
             f"{n} measurements from {meta['path']}: {n - len(errors)} identified, "
             f"{len(errors)} with an error. Identification with 95 % profile-likelihood "
             f"intervals on {space_text(meta)}; diagnosis: "
             f"{'yes' if meta['diagnose'] else 'no'}. "
             f"{meta['seconds']:.1f} s on {meta['workers']} worker(s)"
             + (f", {meta['resumed']} measurements taken from a run cut short"
                if meta.get("resumed") else "") + ".", ""]
    if "group" in df.columns:
        lines += _group_lines(df)
    lines += ["## Group comparison", "", *[f"- {t}" for t in notes], "",
              markdown_table(comparison, (("protocol",) if any("protocol" in r for r in
                                                              comparison) else ())
                             + COMPARISON_COLUMNS, digits=3, align=False), "",
              "median_change_percent: median change of X1d in % (between groups: difference "
              "of the median changes); ci: bootstrap 95 % interval; effect size: rank-biserial "
              "correlation.", ""]
    if df["cause"].notna().any():
        lines += _cause_lines(df)
    if len(errors):
        lines += _error_lines(errors, id_cols)
    lines += [f"Written {meta['created_utc']} by skinsuction {meta['version']}.", ""]
    return "\n".join(lines)


# ------------------------------------------------------------------ the files
def write_study_files(out: Path, df, id_cols, comparison, notes, meta) -> dict:
    """Write ``curves.parquet``, ``comparison.csv``, ``summary.md`` and ``study.json``.

    Parameters
    ----------
    out : Path
        The study's output folder.
    df, id_cols : pandas.DataFrame, list of str
        The study's frame and its id columns (:func:`study_frame`).
    comparison, notes : list
        The group comparison and its notes.
    meta : dict
        The study's record: in the Parquet metadata (``skinsuction`` key) and
        ``study.json``.

    Returns
    -------
    dict
        ``{"curves", "comparison", "summary", "study": Path}``.
    """
    import pandas as pd
    import pyarrow as pa
    import pyarrow.parquet as pq

    from skinsuction._files import atomic_output

    paths = {"curves": out / "curves.parquet", "comparison": out / "comparison.csv",
             "summary": out / "summary.md", "study": out / "study.json"}
    table = pa.Table.from_pandas(df, preserve_index=False)
    table = table.replace_schema_metadata({**(table.schema.metadata or {}),
                                           b"skinsuction": dumps(meta, default=str).encode()})
    with atomic_output(paths["curves"]) as tmp:
        pq.write_table(table, tmp)
    write_table(pd.DataFrame(comparison), paths["comparison"])
    write_text(paths["summary"], summary_markdown(df, id_cols, comparison, notes, meta))
    write_json(paths["study"], {**meta, "comparison": comparison, "notes": notes},
               indent=1, ensure_ascii=True, default=str)
    return paths
