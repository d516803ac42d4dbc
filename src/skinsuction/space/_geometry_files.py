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

__all__ = ["geometry_file_for", "default_geometry_file", "ship_geometry_space",
           "unpack_geometry_space"]


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
    git = git_info(repo)  # before the copy, which is itself a change of the checkout
    with atomic_output(out / name) as tmp:
        shutil.copyfile(built_file, tmp)
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


def unpack_geometry_space(space_file, jobs: dict, out_dir, *, cause=None,
                          source_hash: str, check: int = 1, seed: int = 0) -> dict:
    """Write a geometry space's rays back into the workflow's job files, to extend its grid.

    A shipped space keeps its rays but not the job files it was assembled from, so a
    grid with more nodes (``scale_free_space.geometry.causes.t_d_over_a_of``) would
    solve every node again.  Each job whose rays the file holds becomes a job file as
    :func:`compute_bundle` writes it, once ``check`` of its rays (drawn with ``seed``),
    solved afresh, equal the file's to the 6e-8 of M it stores: the rays are today's
    FE model's, and the job file records today's FE code hash.  Their CPU was counted
    in the file they come from (``seconds`` None).  A job file already there (a build
    cut short, its files carried to another machine) is kept; if another FE code
    solved it, it is restamped with today's hash once ``check`` of its own rays solved
    afresh equal it (``restamped_from`` records the old hash and the rays checked), so
    that it assembles beside today's files; else the build stops, naming the ray.

    Parameters
    ----------
    space_file : path-like
        A geometry space file (built or shipped).
    jobs : dict
        Job name -> ``(t_d/a node, t_h/a nodes)``: the workflow's jobs of this model.
    out_dir : path-like
        The job files' folder; an existing job file is kept as it is.
    cause : Cause, optional
        The file's cause (None: the neo-Hookean space).
    source_hash : str
        Today's FE code hash, the workflow's ``code`` of its ray jobs.
    check, seed : int
        Rays solved afresh per job file written, and the seed that draws them.

    Returns
    -------
    dict
        Job name -> "written", "kept" (its file existed), "restamped" (its file existed,
        solved by other FE code, checked) or "not in the file".

    Raises
    ------
    ValueError
        Naming the ray whose fresh solve differs (the FE model changed: rebuild it), or
        a cause that is not the file's.
    """
    import numpy as np
    import pandas as pd

    from skinsuction._files import file_sha256
    from skinsuction.provenance import collect

    from ._geometry_space import cause_coordinates
    from ._storage import _write_parquet

    space = read_geometry_space(space_file)
    _, meta = _read_parquet(space_file)
    if (cause is None) != (space.cause is None) or (
            cause is not None and (cause.name != space.cause
                                   or cause_coordinates(cause) != list(space.coordinates))):
        raise ValueError(f"{space_file}: holds the rays of {space.cause or 'neo_hookean'}"
                         f" {space.coordinates or ''}, not of the cause given")
    spec = space.spec
    pressures = np.asarray(spec.pressures_mbar, float)
    ids = space.grid.ray_ids(spec, cause=cause)
    rows = dict(zip(ids, space.deflection.reshape(len(ids), pressures.size)))
    stopped, fallback = meta.get("stopped_early") or {}, meta.get("mesh_fallback") or {}
    source = {"file": str(space_file), "sha256": file_sha256(space_file)}
    rng, out_dir, done = np.random.default_rng(seed), Path(out_dir), {}
    out_dir.mkdir(parents=True, exist_ok=True)
    for name, (td, ths) in jobs.items():
        path = out_dir / f"{name}.parquet"
        job_ids = space.grid.ray_ids(spec, td, cause, ths)
        if path.exists():
            done[name] = _restamp(path, source_hash, spec, check, rng)
            continue
        if not all(rid in rows for rid in job_ids):
            done[name] = "not in the file"
            continue
        checked = [job_ids[k] for k in rng.choice(len(job_ids), size=min(check, len(job_ids)),
                                                  replace=False)]
        for rid in checked:
            _same_as_fresh(rid, rows[rid], spec, space_file)
        frame = pd.DataFrame({
            "ray_id": np.repeat(job_ids, pressures.size),
            "pressure_mbar": np.tile(pressures, len(job_ids)),
            "deflection_mm": np.concatenate([rows[rid] for rid in job_ids])})
        infos = {rid: {"converged": rid not in stopped,
                       "last_converged_mbar": stopped.get(rid, float(pressures[-1])),
                       "mesh_fallback": fallback.get(rid, 0), "seconds": None}
                 for rid in job_ids}
        _write_parquet(frame, path, {
            "rays": infos, "mesh": spec.mesh, "mesh_fallback": [dict(f) for f in spec.fallback],
            "fallback_below_mbar": None, "provenance": collect(),
            "bundle_id": f"geometry__{name}", "source_hash": {"model": source_hash},
            "unpacked_from": {**source, "checked_afresh": checked}})
        done[name] = "written"
    return done


def _restamp(path, source_hash, spec, check, rng) -> str:
    """A job file solved by other FE code: "restamped" with today's hash once ``check``
    of its rays solved afresh equal its own (a build resumed after a change of the code
    that leaves the rays as they were); "kept" if it has today's hash already."""
    import numpy as np

    from ._storage import _read_parquet, _write_parquet

    frame, meta = _read_parquet(path)
    old = (meta.get("source_hash") or {}).get("model")
    if old == source_hash:
        return "kept"
    ids = list(dict.fromkeys(frame["ray_id"]))
    checked = [ids[k] for k in rng.choice(len(ids), size=min(check, len(ids)), replace=False)]
    for rid in checked:
        rows = frame[frame["ray_id"] == rid].sort_values("pressure_mbar")
        if not np.array_equal(rows["pressure_mbar"].to_numpy(float),
                              np.asarray(spec.pressures_mbar, float)):
            raise ValueError(f"{path}: ray {rid} is not on the space's pressures")
        _same_as_fresh(rid, rows["deflection_mm"].to_numpy(float), spec, path)
    _write_parquet(frame, path, {**meta, "source_hash": {"model": source_hash},
                                 "restamped_from": {"source_hash": old,
                                                    "checked_afresh": checked}})
    return "restamped"


def _same_as_fresh(rid, stored, spec, space_file) -> None:
    """Solve ``rid`` afresh; raise unless it equals ``stored`` (NaN where it stopped)."""
    import numpy as np

    from ._ray_solve import compute_ray

    curve, _, info = compute_ray(rid, spec.pressures_mbar, spec.mesh, list(spec.fallback))
    fresh = np.asarray(curve.deflection_mm, float)
    if not info["converged"]:
        fresh[~(np.asarray(spec.pressures_mbar) <= info["last_converged_mbar"])] = np.nan
    ok = np.isfinite(fresh)
    if not (np.array_equal(ok, np.isfinite(stored))
            and np.allclose(stored[ok], fresh[ok], rtol=1e-6, atol=1e-9)):
        raise ValueError(f"{space_file}: ray {rid} solved afresh differs from the file's "
                         "(the FE model changed since it was built): rebuild the space")
