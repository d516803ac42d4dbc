"""The default scale-free space: the workflow's build here, else the one shipped with skinsuction.

``skinsuction identify``, ``diagnose`` and ``study`` read the scale-free
simulated space.  Which one, when no ``--space`` is given, is decided here and
nowhere else (:func:`resolve_space`):

1. ``results/simulated_space/scale_free/`` under the working directory, if it
   holds ``neo_hookean.parquet``: the user's own build of the workflow
   (``snakemake --cores 2 scale_free_space``);
2. otherwise the default space shipped with the package
   (``skinsuction/data/scale_free/``: one Parquet file per model, no ray
   bundles, and ``PROVENANCE.json``: the configuration section, the commit of
   the code that built it, the date, the commands, and per file its SHA-256
   and row count).

An explicit path always wins.  Every command records which space it used
(:attr:`SpaceSource.description`), and says so plainly for the shipped one.

The shipped files must agree with their ``PROVENANCE.json``
(:func:`verify_shipped_files`); ``ship_space`` copies a build into the package
(the workflow's developer rule ``ship_scale_free_space``) and writes it.
Whether a fresh build agrees with the shipped space, ray by ray, is
:mod:`._shipped_check`'s.

Examples
--------
In a folder without a build of the workflow, the default is the shipped space:

>>> import tempfile
>>> default_space_dir(cwd=tempfile.mkdtemp()) == SHIPPED_SPACE_DIR
True
>>> resolve_space("my_space").source
'given'
"""

from __future__ import annotations

import datetime as _dt
import json
import logging
from dataclasses import dataclass, field
from pathlib import Path

from skinsuction._files import atomic_output, file_sha256

from ._causes import BASELINE
from ._ray_space import read_ray_space

log = logging.getLogger(__name__)

__all__ = [
    "WORKFLOW_SPACE_DIR", "SHIPPED_SPACE_DIR", "PROVENANCE_FILE", "SpaceSource",
    "default_space_dir", "resolve_space", "shipped_provenance", "verify_shipped_files",
    "ship_space",
]

#: Where the workflow writes the scale-free space, relative to the working directory.
WORKFLOW_SPACE_DIR = "results/simulated_space/scale_free"

#: The default scale-free space shipped with the package (package data).
SHIPPED_SPACE_DIR = Path(__file__).resolve().parent.parent / "data" / "scale_free"

#: The shipped space's provenance, next to its files.
PROVENANCE_FILE = "PROVENANCE.json"


# ------------------------------------------------------------------ resolution
@dataclass(frozen=True)
class SpaceSource:
    """Which simulated space a command reads, and why.

    Attributes
    ----------
    path : Path
        The space (a folder of the scale-free layout, or a file).
    source : {"given", "workflow", "shipped"}
        Given explicitly (``--space``), the workflow's build found under the
        working directory, or the default space shipped with the package.
    description : str
        One sentence for reports and the command line.
    provenance : dict or None
        ``PROVENANCE.json`` of the shipped space.
    """

    path: Path
    source: str
    description: str
    provenance: dict | None = field(default=None, compare=False)

    def info(self) -> dict:
        """JSON-able record for result files (``identification.json``, reports, studies).

        Returns
        -------
        dict
            ``source``, ``description`` and, for the shipped space, its version,
            commits, date, commands and the SHA-256 of its ``PROVENANCE.json``.
        """
        out = {"source": self.source, "description": self.description}
        if self.source == "shipped":
            p = self.provenance or {}
            out["shipped"] = {k: p.get(k) for k in (
                "skinsuction_version", "git_commit", "git_dirty", "created_utc", "config_file",
                "build_command")}
            prov_file = (self.path.parent if self.path.is_file() else self.path) / PROVENANCE_FILE
            out["shipped"]["provenance_sha256"] = (
                file_sha256(prov_file) if prov_file.is_file() else None)
        return out


def _has_space(folder: Path) -> bool:
    return (folder / f"{BASELINE}.parquet").is_file()


def default_space_dir(cwd=None) -> Path:
    """The default scale-free space: the workflow's build under ``cwd`` if any, else the shipped one.

    The workflow's build counts when ``results/simulated_space/scale_free/neo_hookean.parquet``
    exists relative to ``cwd`` (default: the working directory); it is then returned as that
    relative path, as the workflow names it.

    Parameters
    ----------
    cwd : path-like, optional
        The folder to look in (default: the working directory).

    Returns
    -------
    Path
    """
    base = Path(cwd) if cwd is not None else Path()
    if _has_space(base / WORKFLOW_SPACE_DIR):
        return base / WORKFLOW_SPACE_DIR if cwd is not None else Path(WORKFLOW_SPACE_DIR)
    return SHIPPED_SPACE_DIR


def shipped_provenance(folder=SHIPPED_SPACE_DIR) -> dict | None:
    """``PROVENANCE.json`` of a shipped space.

    Parameters
    ----------
    folder : path-like
        The shipped space's folder (default: the package's).

    Returns
    -------
    dict or None
        None if the folder has no ``PROVENANCE.json``.
    """
    path = Path(folder) / PROVENANCE_FILE
    if not path.is_file():
        return None
    return json.loads(path.read_text(encoding="utf-8"))


def _is_shipped(path: Path) -> bool:
    try:
        p = path.resolve()
    except OSError:
        return False
    if p.is_file():
        p = p.parent
    return p == SHIPPED_SPACE_DIR


def _shipped_text(prov: dict | None) -> str:
    from skinsuction import __version__

    if not prov:
        return (f"the default space shipped with skinsuction {__version__} (no "
                f"{PROVENANCE_FILE}: provenance unknown)")
    commit = prov.get("git_commit") or "unknown"
    dirty = " with uncommitted changes" if prov.get("git_dirty") else ""
    when = str(prov.get("created_utc") or "")[:10]
    config = prov.get("config_file") or "a custom configuration"
    return (f"the default space shipped with skinsuction {__version__}, built at commit "
            f"{commit[:12]}{dirty} from the scale_free_space section of {config}"
            + (f" on {when}" if when else ""))


def resolve_space(space=None, cwd=None) -> SpaceSource:
    """The space a command reads: ``space`` if given, else :func:`default_space_dir`.

    An explicit path is returned as given (a missing one is reported by the
    reader, naming it); a path that is the shipped folder is described as such.

    Parameters
    ----------
    space : path-like, optional
        The space given (``--space``).
    cwd : path-like, optional
        Where to look for the workflow's build (default: the working directory).

    Returns
    -------
    SpaceSource

    Raises
    ------
    skinsuction.errors.InputError
        With no ``space``, when there is neither a build of the workflow under the
        working directory nor a shipped space in this installation.
    """
    if space is not None:
        path = Path(space)
        if _is_shipped(path):
            prov = shipped_provenance()
            return SpaceSource(path, "shipped", _shipped_text(prov), prov)
        return SpaceSource(path, "given", f"the space given: {path}")
    path = default_space_dir(cwd)
    if path != SHIPPED_SPACE_DIR:
        return SpaceSource(path, "workflow",
                           f"the workflow's build in {WORKFLOW_SPACE_DIR} of the working "
                           "directory (preferred to the default space shipped with skinsuction)")
    if not _has_space(path):
        from skinsuction.errors import InputError

        raise InputError(
            f"no simulated space: {WORKFLOW_SPACE_DIR} is not built in the working directory "
            f"and this installation of skinsuction ships none ({path} has no "
            f"{BASELINE}.parquet); build it with the workflow (`snakemake --cores 2 "
            "scale_free_space`) or give one with --space")
    prov = shipped_provenance(path)
    return SpaceSource(path, "shipped", _shipped_text(prov), prov)


# ------------------------------------------------------- the shipped files themselves
def _file_record(path: Path) -> dict:
    import pyarrow.parquet as pq

    meta = pq.read_metadata(path)
    space = read_ray_space(path)
    return {"sha256": file_sha256(path), "rows": int(meta.num_rows),
            "bytes": path.stat().st_size, "model": space.name,
            "rays": int(space.metadata.get("n_rays", 0)),
            "stopped_early": int(space.metadata.get("n_stopped", 0))}


def verify_shipped_files(folder=SHIPPED_SPACE_DIR) -> list:
    """Problems of a shipped folder against its ``PROVENANCE.json`` (empty: all agree).

    Every file listed must be there with its SHA-256 and row count, and no
    other model file may be; the same for the pair spaces (``pairs/``) and the
    geometry space (``geometry/``) against their own ``PROVENANCE.json``.

    Parameters
    ----------
    folder : path-like
        The shipped space's folder (default: the package's).

    Returns
    -------
    list of str
        One sentence per problem; empty when every file agrees.
    """
    import pyarrow.parquet as pq

    folder = Path(folder)
    prov = shipped_provenance(folder)
    if prov is None:
        return [f"{folder}: no {PROVENANCE_FILE}"]
    problems = []
    listed = prov.get("files") or {}
    if f"{BASELINE}.parquet" not in listed:
        problems.append(f"{PROVENANCE_FILE} lists no {BASELINE}.parquet")
    for name, rec in sorted(listed.items()):
        path = folder / name
        if not path.is_file():
            problems.append(f"{name}: listed in {PROVENANCE_FILE} but missing")
            continue
        sha = file_sha256(path)
        if sha != rec.get("sha256"):
            problems.append(f"{name}: SHA-256 {sha[:12]}, {PROVENANCE_FILE} says "
                            f"{str(rec.get('sha256'))[:12]}")
        rows = pq.read_metadata(path).num_rows
        if rows != rec.get("rows"):
            problems.append(f"{name}: {rows} rows, {PROVENANCE_FILE} says {rec.get('rows')}")
    for path in sorted(folder.glob("*.parquet")):
        if path.name not in listed:
            problems.append(f"{path.name}: not listed in {PROVENANCE_FILE}")
    return problems + _verify_subfolder(folder, "pairs") + _verify_subfolder(folder, "geometry")


def _verify_subfolder(folder: Path, sub: str) -> list:
    """A subfolder's files (the pair spaces, the geometry space) against its own
    ``PROVENANCE.json``."""
    where = folder / sub
    files = sorted(where.glob("*.parquet"))
    prov = shipped_provenance(where) if where.is_dir() else None
    if prov is None:
        return [f"{sub}/{p.name}: no {sub}/{PROVENANCE_FILE}" for p in files]
    listed = prov.get("files") or {}
    out = [f"{sub}/{p.name}: not listed in {sub}/{PROVENANCE_FILE}" for p in files
           if p.name not in listed]
    for name, rec in sorted(listed.items()):
        path = where / name
        if not path.is_file():
            out.append(f"{sub}/{name}: listed in {sub}/{PROVENANCE_FILE} but missing")
        elif file_sha256(path) != rec.get("sha256"):
            out.append(f"{sub}/{name}: its SHA-256 differs from {sub}/{PROVENANCE_FILE}'s")
    return out


def _normal(obj):
    from skinsuction.provenance import jsonable

    return json.loads(json.dumps(jsonable(obj), sort_keys=True))


# ------------------------------------------------------------------- shipping
def _write_compact(src, dest) -> None:
    """Copy a space file without each ray's mesh settings in its solver record.

    They repeat the ray specification's mesh (or, for a ray a fallback carried, the
    fallback of its ``mesh_fallback`` index) on every ray: a third of the file, which
    the package data need not carry.  The rays and everything else are copied as
    they are.
    """
    import pyarrow.parquet as pq

    from ._storage import METADATA_KEY

    table = pq.read_table(src)
    schema_meta = dict(table.schema.metadata or {})
    meta = json.loads(schema_meta.get(METADATA_KEY, b"{}"))
    for info in (meta.get("rays") or {}).values():
        (info.get("curve_info") or {}).pop("mesh", None)
    schema_meta[METADATA_KEY] = json.dumps(meta, sort_keys=True).encode()
    pq.write_table(table.replace_schema_metadata(schema_meta), dest)


def ship_space(built_dir, dest=SHIPPED_SPACE_DIR, *, config_file: str | None = None,
               build_command: str | None = None, ship_command: str | None = None,
               repo=None) -> dict:
    """Copy a build of the scale-free space (its model files) into ``dest`` with ``PROVENANCE.json``.

    The ray bundles (``rays/``) are not copied.  Model files of ``dest`` that the
    build does not have are removed; ``PROVENANCE.json`` is written last (each
    file atomically).  It records the configuration section (from the space's own
    metadata), the effective ray specification and the causes, the commit of the
    code (``git rev-parse HEAD`` of ``repo``) and the build's own commit, the
    date, the commands, and per file its SHA-256, row count, size and rays.

    Parameters
    ----------
    built_dir : path-like
        The build (``results/simulated_space/scale_free``).
    dest : path-like
        Where to ship it (default: the package's data folder).
    config_file : str, optional
        The configuration file the build came from, for the record.
    build_command, ship_command : str, optional
        The commands that built and shipped it, for the record.
    repo : path-like, optional
        The git repository whose commit is recorded (default: the working directory's).

    Returns
    -------
    dict
        The provenance record written to ``PROVENANCE.json``.
    """
    from skinsuction import __version__
    from skinsuction.provenance import git_info, jsonable

    built_dir, dest = Path(built_dir), Path(dest)
    files = sorted(built_dir.glob("*.parquet"))
    names = [p.name for p in files]
    if f"{BASELINE}.parquet" not in names:
        raise FileNotFoundError(f"{built_dir}: no {BASELINE}.parquet to ship (build the space "
                                "first: `snakemake --cores 2 scale_free_space`)")
    spaces = {p.name: read_ray_space(p) for p in files}
    base = spaces[f"{BASELINE}.parquet"]
    for name, s in spaces.items():
        if _normal(s.spec.to_dict()) != _normal(base.spec.to_dict()):
            raise ValueError(f"{built_dir / name}: its ray specification differs from "
                             f"{BASELINE}.parquet's (a stale file? rebuild the space)")
    meta = base.metadata
    build_git = meta.get("git") or {}
    git = git_info(repo)
    if build_git.get("commit") and git.get("commit") and build_git["commit"] != git["commit"]:
        log.warning("the space was built at commit %s, the code is now at %s: the provenance "
                    "records both", build_git["commit"], git["commit"])
    dest.mkdir(parents=True, exist_ok=True)
    for name in names:
        with atomic_output(dest / name) as tmp:
            _write_compact(built_dir / name, tmp)
    for stale in dest.glob("*.parquet"):
        if stale.name not in names:
            stale.unlink()
    causes = {s.cause.name: s.cause.to_dict() for s in spaces.values() if s.cause is not None}
    record = {
        "what": "the default scale-free simulated space of skinsuction: one Parquet file per "
                "model (neo_hookean and one per cause), the ray bundles left out; read by "
                "identify, diagnose and study when results/simulated_space/scale_free is not "
                "built in the working directory",
        "skinsuction_version": __version__,
        "git_commit": build_git.get("commit") or git.get("commit"),
        "git_dirty": build_git.get("dirty") if build_git.get("commit") else git.get("dirty"),
        "shipped_from_commit": git.get("commit"),
        "shipped_from_dirty": git.get("dirty"),
        "created_utc": meta.get("created_utc"),
        "shipped_utc": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "config_file": config_file,
        "config_section": (meta.get("config") or {}).get("scale_free_space"),
        "study_mesh": {k: (meta.get("config") or {}).get(k) for k in ("mesh", "mesh_fallback")},
        "ray_spec": base.spec.to_dict(),
        "causes": causes,
        "build_command": build_command,
        "ship_command": ship_command,
        "versions": meta.get("versions"),
        "platform": meta.get("platform"),
        "files": {name: _file_record(dest / name) for name in names},
    }
    record = jsonable(record)
    with atomic_output(dest / PROVENANCE_FILE) as tmp:
        tmp.write_text(json.dumps(record, indent=1, sort_keys=False) + "\n", encoding="utf-8")
    log.info("shipped %d files from %s to %s (commit %s)", len(names), built_dir, dest,
             record["git_commit"])
    return record
