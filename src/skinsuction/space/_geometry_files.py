"""Where the geometry spaces are found, and how they are shipped with the package.

The spaces themselves (:class:`GeometrySpace`, the neo-Hookean one and the causes')
are in :mod:`._geometry_space`; this module finds the files a command reads (a
space's own ``geometry/`` folder, the workflow's build, the shipped copy) and
copies a built one into the package with its provenance.
"""

from __future__ import annotations

from pathlib import Path

from ._geometry_space import GEOMETRY_FILE, GEOMETRY_FOLDER, read_geometry_space
from ._storage import _read_parquet

__all__ = ["geometry_file_for", "default_geometry_file", "ship_geometry_space"]


def geometry_file_for(space_path, solve_on_demand=True):
    """The geometry space that rays on demand read first (their ``geometry``).

    Parameters
    ----------
    space_path : path-like
        The scale-free space (its folder or its ``neo_hookean.parquet``).
    solve_on_demand : bool or "always"
        "always": every ray solved, no geometry space.

    Returns
    -------
    Path, "auto" or None
        The one in the space's folder (``geometry/neo_hookean.parquet``), else
        "auto" (the default one, :func:`default_geometry_file`); None for "always".
    """
    if solve_on_demand == "always":
        return None
    space_path = Path(space_path)
    folder = space_path if space_path.is_dir() else space_path.parent
    own = folder / GEOMETRY_FOLDER / GEOMETRY_FILE
    return own if own.is_file() else "auto"


def default_geometry_file(cwd=None) -> Path | None:
    """The default geometry space: the workflow's build under ``cwd``, else the shipped one.

    Returns
    -------
    Path or None
        None where neither exists.
    """
    from ._shipped import SHIPPED_SPACE_DIR, WORKFLOW_SPACE_DIR

    base = Path(cwd) if cwd is not None else Path()
    for folder in (base / WORKFLOW_SPACE_DIR, Path(SHIPPED_SPACE_DIR)):
        path = folder / GEOMETRY_FOLDER / GEOMETRY_FILE
        if path.is_file():
            return path
    return None


def ship_geometry_space(built_file, dest=None, *, build_command: str | None = None,
                        repo=None) -> dict:
    """Copy a built geometry space into the package (``<dest>/geometry/``) and record it
    in that folder's ``PROVENANCE.json``: the file's SHA-256 and size, the grid, the ray
    specification, the rays stopped early and the CPU they took, and the commit
    shipped from.  The records of the folder's other files (the neo-Hookean space, the
    causes') are kept.

    Parameters
    ----------
    built_file : path-like
        ``results/simulated_space/scale_free/geometry/<model>.parquet``.
    dest : path-like, optional
        The shipped space's folder (default: the package's).
    build_command : str, optional
        The command that built it, for the record.
    repo : path-like, optional
        The git repository whose commit is recorded.

    Returns
    -------
    dict
        The provenance record written (the whole folder's).
    """
    import datetime as _dt
    import json
    import shutil

    from skinsuction import __version__
    from skinsuction._files import atomic_output, file_sha256
    from skinsuction.provenance import git_info, jsonable

    from ._shipped import PROVENANCE_FILE, SHIPPED_SPACE_DIR, shipped_provenance

    out = Path(dest or SHIPPED_SPACE_DIR) / GEOMETRY_FOLDER
    name = Path(built_file).name
    space = read_geometry_space(built_file)
    _, meta = _read_parquet(built_file)
    out.mkdir(parents=True, exist_ok=True)
    with atomic_output(out / name) as tmp:
        shutil.copyfile(built_file, tmp)
    git = git_info(repo)
    record = (shipped_provenance(out) if (out / PROVENANCE_FILE).is_file() else None) or {}
    files = dict(record.get("files") or {})
    files[name] = jsonable({
        "model": space.cause or "neo_hookean",
        "sha256": file_sha256(out / name), "bytes": (out / name).stat().st_size,
        "shipped_from_commit": git.get("commit"), "shipped_from_dirty": git.get("dirty"),
        "shipped_utc": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "build_command": build_command, "built": space.provenance,
        "ray_spec": space.spec.to_dict(), "grid": space.grid.to_dict(),
        "coordinates": None if space.cause is None else list(space.coordinates),
        "rays": meta.get("rays"), "stopped_early": len(meta.get("stopped_early") or {}),
        "mesh_fallback": len(meta.get("mesh_fallback") or {}), "cpu_s": meta.get("cpu_s"),
    })
    record = {
        "what": "rays of skinsuction's default space over the subject's geometry (t_d/a, "
                "t_h/a at a = 1 mm), the neo-Hookean model's and the causes': identify, "
                "diagnose and study read a subject's rays off them instead of solving them",
        "skinsuction_version": __version__, "files": dict(sorted(files.items())),
    }
    with atomic_output(out / PROVENANCE_FILE) as tmp:
        tmp.write_text(json.dumps(record, indent=1) + "\n", encoding="utf-8")
    return record
