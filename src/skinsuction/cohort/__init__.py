"""Whole clinical studies at once: every curve identified (with intervals) and diagnosed.

A study is a folder of measured CSVs (one measurement per file, or long files
with id columns) or one long CSV whose columns besides ``probe_mm``,
``pressure_mbar``, ``deflection_mm`` and ``curve`` are ids (``subject``,
``site``, ``visit``, ``group``, ...).  A file's ``# key: value`` lines and an
optional ``manifest.csv`` (a ``file`` column and id columns) or
``manifest.yaml`` (``{file: {key: value}}``) in the folder add ids.  Every
measurement keeps its ids end to end; one that the loader rejects becomes a row
with its error, and the study goes on.

:func:`run_study` identifies (X1d, X1h) of each measurement with 95 %
profile-likelihood intervals (weighted objective when both probes are present,
else the single objective of its probe), diagnoses it (optional), and writes

* ``curves.parquet``: one row per measurement (ids, source and its SHA-256,
  estimates with intervals, E, noise, misfit, named cause, extended parameter
  with its interval, gain, warnings, error);
* ``comparison.csv`` and ``summary.md``: the group comparison
  (:func:`compare_groups`) and the counts;
* figures: parameter distributions per group, paired before/after per subject
  (with a ``visit`` column), share of each named cause per group;
* ``reports/<row>/`` per measurement (identification and diagnosis files),
  only if asked (big studies would write thousands of folders).

The group comparison (:func:`compare_groups`) is described in ``_compare``; the
measurements are found by ``_discover``, each becomes a row in ``_rows`` (the
per-curve work), and ``_tables`` writes the frame, ``summary.md`` and the files.
"""

from ._compare import compare_groups
from ._discover import discover
from ._rows import RESULT_COLUMNS, study_rows
from ._run import run_study

__all__ = ["discover", "run_study", "compare_groups", "study_rows", "RESULT_COLUMNS"]
