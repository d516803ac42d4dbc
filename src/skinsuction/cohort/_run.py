"""Running a study: discover the measurements, analyse each, write the outputs.

The steps are modules of their own: :mod:`._discover` (the measurements and their
ids), :mod:`._rows` (the per-curve work: identification, diagnosis, reports),
:mod:`._compare` (the group tests) and :mod:`._tables` (the frame, ``summary.md``
and the files); :func:`run_study` composes them.
"""

from __future__ import annotations

import datetime as _dt
import sys
import time
from pathlib import Path

from ._checkpoint import CHECKPOINT_FILE, Checkpoint
from ._compare import compare_groups
from ._discover import discover
from ._rows import RESULT_COLUMNS, study_rows
from ._tables import space_text, study_frame, write_study_files

__all__ = ["discover", "run_study", "study_rows", "RESULT_COLUMNS"]


def run_study(path, out_dir, *, space_dir=None,
              diagnose: bool = True, repeats: int = 2, seed: int = 0, level: float = 0.95,
              workers: int = 1, reports: bool = False, name: str | None = None,
              diagnosis_settings: dict | None = None, figures: bool = True,
              progress=None, space=None, ray_spaces=None, resume: bool = True) -> dict:
    """Identify (and diagnose) every measurement of a study and write its outputs.

    Parameters
    ----------
    path : path-like
        A folder of measured CSVs or one long CSV (see the module docstring).
    out_dir : path-like
        Output folder (``curves.parquet``, ``comparison.csv``, ``summary.md``,
        figures, ``study.json``).
    space_dir : path-like, optional
        The scale-free space (default: :func:`skinsuction.space.resolve_space`, the
        workflow's build or the shipped one; ``study.json`` and ``summary.md`` say which).
    diagnose : bool
        Diagnose every measurement too (slower: seconds each).
    repeats, seed, level :
        Window focusing runs per identification, the study's seed (measurement
        ``i`` uses ``seed + i``), the confidence level of the intervals.
    workers, reports :
        Processes; also write each measurement's identification and diagnosis files.
    space, ray_spaces : optional
        A :class:`skinsuction.space.LoadedSpace` and the ray spaces
        ``{name: RaySpace}`` instead of reading ``space_dir`` (tests, notebooks).
    resume : bool
        Take the rows a run cut short had finished (``out_dir/rows.partial.jsonl``,
        same files, space, settings and version); False: afresh (docs/studies.md).

    Returns
    -------
    dict
        Paths written, counts and timings.

    Examples
    --------
    Two subjects, two visits each, identified (not diagnosed) on a small grid
    space filled by the analytic surrogate; the third file is broken and
    becomes a row with its error:

    >>> import pathlib, tempfile
    >>> import pandas as pd
    >>> from skinsuction.identify import surrogate_deflection, write_surrogate_space
    >>> root = pathlib.Path(tempfile.mkdtemp())
    >>> p = [0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0, 90.0, 100.0]
    >>> write_surrogate_space(root / "space.parquet", [0.01, 0.02, 0.03, 0.04, 0.05],
    ...                       [1e-4, 3e-4, 5e-4, 7e-4, 9e-4], p)
    >>> (root / "study").mkdir()
    >>> for subject, x1d in (("S1", 0.025), ("S2", 0.035)):
    ...     for visit, f in ((1, 1.0), (2, 1.2)):
    ...         m = surrogate_deflection(x1d * f, 5e-4, p, 6.0)
    ...         text = f"# subject: {subject}\\n# visit: {visit}\\nprobe_mm,pressure_mbar,deflection_mm\\n"
    ...         text += "".join(f"6,{a:g},{b:.6f}\\n" for a, b in zip(p, m))
    ...         _ = (root / "study" / f"{subject}_v{visit}.csv").write_text(text)
    >>> _ = (root / "study" / "S3_v1.csv").write_text("probe_mm;pressure_mbar\\n")
    >>> r = run_study(root / "study", root / "out", space_dir=root / "space.parquet",
    ...               diagnose=False, figures=False, progress=False)
    >>> rows = pd.read_parquet(root / "out" / "curves.parquet")
    >>> len(rows), int(rows["error"].notna().sum())
    (5, 1)
    >>> truth = [0.025, 0.03, 0.035, 0.042]  # within the error of this coarse 5 x 5 grid:
    >>> est = rows.dropna(subset=["x1d_mpa"])["x1d_mpa"].to_numpy()
    >>> bool(abs(est / truth - 1).max() < 0.03)
    True
    """
    t0 = time.perf_counter()
    if not Path(path).exists():
        raise FileNotFoundError(f"{path}: no such study folder or file")
    space_dir, space_info = _which_space(space_dir, space, diagnose and ray_spaces is None)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    space, entries = _measurements(path, space_dir, space)
    ray_spaces, pairs, settings = (_diagnosis(space_dir, ray_spaces, diagnosis_settings, level,
                                              reports) if diagnose else (None, None, None))
    checkpoint = _checkpoint(out, resume, progress, space=str(space_dir),
                             space_sha256=space.info.get("sha256"),
                             ray_spaces=sorted(ray_spaces or ()), pairs=sorted(pairs or ()),
                             settings=settings.__dict__ if settings is not None else None,
                             repeats=int(repeats), seed=int(seed), level=float(level),
                             reports=bool(reports))
    with checkpoint:
        rows = study_rows(entries, space=space, ray_spaces=ray_spaces, settings=settings,
                          pair_spaces=pairs, repeats=repeats, seed=seed, level=level,
                          workers=workers, reports_dir=(out / "reports") if reports else None,
                          progress=progress, checkpoint=checkpoint)
    df, id_cols = study_frame(rows)
    comparison, notes = compare_groups(df, seed=seed)
    seconds = time.perf_counter() - t0
    meta = _record(name or Path(path).stem, path, space_dir, space, space_info, settings,
                   df, seconds, diagnose=diagnose, repeats=repeats, seed=seed, level=level,
                   workers=workers)
    meta["resumed"] = checkpoint.resumed
    paths = _write(out, df, id_cols, comparison, notes, meta, figures)
    checkpoint.remove()  # every row is in the study's files now
    return {"paths": paths, "space": space_text(meta, markdown=False),
            "measurements": int(len(df)), "errors": meta["errors"], "seconds": seconds,
            "comparison": comparison, "resumed": checkpoint.resumed, "notes": notes}


def _write(out, df, id_cols, comparison, notes, meta, figures: bool) -> dict:
    """The study's files (and figures): name -> path."""
    paths = write_study_files(out, df, id_cols, comparison, notes, meta)
    if figures:
        from skinsuction.figures.cohort import write_study_figures

        paths.update(write_study_figures(df, out))
    return {k: str(v) for k, v in paths.items()}


def _checkpoint(out, resume, progress, **fingerprint) -> Checkpoint:
    """The study's kept rows (:class:`Checkpoint`), said aloud when some are reused or set
    aside; the fingerprint is what the rows depend on, with the package's version and a
    hash of its sources and data (a fix between a cut and its rerun, as the ramps'
    thickness move of 29 November 2026, would otherwise mix rows of both codes)."""
    from skinsuction import __version__
    from skinsuction.provenance import source_hash

    checkpoint = Checkpoint(out / CHECKPOINT_FILE, {**fingerprint, "version": __version__,
                                                    "source": source_hash(".")},
                            resume=resume)
    if progress is not False and (checkpoint.resumed or checkpoint.stale):
        print(f"study: {checkpoint.resumed} finished measurements taken from {checkpoint.path}"
              + (f"; rows of other settings kept aside in {checkpoint.stale}"
                 if checkpoint.stale else ""), file=sys.stderr)
    return checkpoint


def _which_space(space_dir, space, need_dir: bool) -> tuple:
    """The space's folder (the default one if None) and what it is, in words."""
    if space is None or space_dir is not None or need_dir:
        from skinsuction.space import resolve_space

        src = resolve_space(space_dir)
        return src.path, src.info()
    return space_dir, {"source": "given", "description": "a space given in memory"}


def _measurements(path, space_dir, space) -> tuple:
    """The loaded space and the study's measurements, checked against its reach."""
    from skinsuction.space import load_space

    space = space if space is not None else load_space(space_dir)
    names = list(space.spaces)
    return space, discover(path, available_probes=space.available_probes,
                           pressure_range_mbar=space.pressure_range(names),
                           range_note=space.range_note(names))


def _diagnosis(space_dir, ray_spaces, diagnosis_settings, level, reports) -> tuple:
    """The ray spaces, the pair spaces that go with them and the settings of the study's
    diagnoses (the neo-Hookean intervals only for the reports: a row has the
    identification's)."""
    from skinsuction.diagnose import Settings
    from skinsuction.space import BASELINE, pairs_for, read_ray_spaces

    ray_spaces = ray_spaces if ray_spaces is not None else read_ray_spaces(space_dir)
    pairs = pairs_for(space_dir, ray_spaces[BASELINE].spec)
    # the study's default: one window focusing run per fit, no holdout (seconds saved
    # per measurement); any decision or fit key of the configuration overrides
    settings = Settings.from_config(None, {"holdout": False, "repeats": 1,
                                           "intervals": "chosen" if reports else "cause",
                                           **(diagnosis_settings or {})}, level=level)
    return ray_spaces, pairs, settings


def _record(name, path, space_dir, space, space_info, settings, df, seconds, *, diagnose,
            repeats, seed, level, workers) -> dict:
    """The study's record: in ``study.json``, ``summary.md`` and the Parquet metadata."""
    from skinsuction import __version__

    return {"name": name, "path": str(path), "space": str(space_dir),
            "space_sha256": space.info.get("sha256"),
            "space_source": space_info["source"],
            "space_description": space_info["description"],
            "space_shipped": space_info.get("shipped"), "diagnose": bool(diagnose),
            "repeats": int(repeats), "seed": int(seed), "level": float(level),
            "workers": int(workers), "seconds": seconds, "version": __version__,
            "created_utc": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
            "measurements": int(len(df)), "errors": int(df["error"].notna().sum()),
            "diagnosis_settings": settings.__dict__ if settings is not None else None}
