"""The measurements of a study: its files, their ids (manifest, header lines), read once."""

from __future__ import annotations

from pathlib import Path

__all__ = ["MANIFESTS", "discover"]

MANIFESTS = ("manifest.csv", "manifest.yaml", "manifest.yml")


def _sha256(path) -> str | None:
    from skinsuction._files import file_sha256

    try:
        return file_sha256(path)
    except OSError:
        return None


def _manifest(folder: Path) -> dict:
    """``{file name: {id: value}}`` from the folder's manifest, if any."""
    for name in MANIFESTS:
        path = folder / name
        if not path.exists():
            continue
        if path.suffix == ".csv":
            import pandas as pd

            table = pd.read_csv(path, dtype=str, keep_default_na=False)
            if "file" not in table.columns:
                raise ValueError(f"{path}: a manifest needs a 'file' column")
            return {r.pop("file"): r for r in table.to_dict("records")}
        import yaml

        try:
            data = yaml.safe_load(path.read_text(encoding="utf-8")) or {}
        except yaml.YAMLError as err:
            raise ValueError(f"{path}: not valid YAML ({' '.join(str(err).split())})") from None
        if not isinstance(data, dict):
            raise ValueError(f"{path}: the manifest must map file names to ids")
        return {str(k): {str(a): str(b) for a, b in (v or {}).items()} for k, v in data.items()}
    return {}


def discover(path, *, available_probes=None, pressure_range_mbar=None, range_note=None) -> list:
    """The measurements of a study: ``[(StudyEntry, sha256)]`` in a stable order.

    Parameters
    ----------
    path : path-like
        A folder (its ``*.csv`` files, sorted, subfolders included, the manifest
        excluded) or one CSV.
    available_probes, pressure_range_mbar, range_note : optional
        The checks of a pressure ramp against the simulated space
        (:func:`skinsuction.measured.read_measurement`).

    Returns
    -------
    list of tuple
        ``(StudyEntry, sha256 of its file)``; each entry's ids include ``file`` (the
        path relative to the folder).  A measurement the loader rejects is an entry
        with its error (a pressure ramp's; a bad time-curve file raises).

    Raises
    ------
    FileNotFoundError
        No such folder or file.
    ValueError
        A folder without CSV files, or a bad manifest.
    """
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such study folder or file")
    if path.is_dir():
        manifest = _manifest(path)
        files = sorted(p for p in path.rglob("*.csv") if p.name not in MANIFESTS)
        if not files:
            raise ValueError(f"{path}: no .csv files in the study folder")
    else:
        manifest, files = {}, [path]
    from skinsuction.measured import MeasuredDataError, StudyEntry, read_measurement

    out = []
    for f in files:
        rel = f.relative_to(path).as_posix() if path.is_dir() else f.name
        ids = {"file": rel, **manifest.get(rel, manifest.get(f.name, {}))}
        sha = _sha256(f)
        try:  # a ramp table's bad measurement is an entry; a bad time file raises
            loaded = read_measurement(f, table=True, ids=ids, available_probes=available_probes,
                                      pressure_range_mbar=pressure_range_mbar,
                                      range_note=range_note)
        except MeasuredDataError as err:
            out.append((StudyEntry(dict(ids), None, str(err), str(f)), sha))
            continue
        if isinstance(loaded, list):
            out += [(entry, sha) for entry in loaded]
        else:
            out.append((_time_entry(f, ids, loaded), sha))
    return out


def _time_entry(path, ids, data):
    """A time-curve file as one measurement (its ``# key: value`` lines are ids); a
    file of several subjects in one long table with ``time_s`` is not read (yet)."""
    from skinsuction.measured import SD_KEYS, StudyEntry

    geometry_keys = set(SD_KEYS) | set(SD_KEYS.values())
    meta = {k: v for k, v in data.metadata.items() if k not in geometry_keys}
    return StudyEntry({**meta, **ids}, data, None, str(path))
