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

The shipped space is only as good as its agreement with the code: the
workflow's ``check_shipped_space`` rule compares a fresh build with it ray by
ray (:func:`compare_ray_spaces`, :func:`check_shipped_space`), and
``tests/test_shipped_space.py`` re-solves a few of its rays on every push.
``ship_space`` copies a build into the package (the workflow's developer rule
``ship_scale_free_space``).

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
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from skinsuction._files import atomic_output, file_sha256, write_table

from ._causes import BASELINE
from ._ray_space import RaySpace, read_ray_space
from ._rays import rays_of

log = logging.getLogger(__name__)

__all__ = [
    "WORKFLOW_SPACE_DIR", "SHIPPED_SPACE_DIR", "PROVENANCE_FILE", "SpaceSource",
    "default_space_dir", "resolve_space", "shipped_provenance", "verify_shipped_files",
    "shipped_check_applies", "compare_ray_spaces", "knife_edge_rays", "check_shipped_space",
    "ShippedSpaceMismatch", "ship_space", "SHIPPED_RTOL", "SHIPPED_ATOL_MM",
]

#: Where the workflow writes the scale-free space, relative to the working directory.
WORKFLOW_SPACE_DIR = "results/simulated_space/scale_free"

#: The default scale-free space shipped with the package (package data).
SHIPPED_SPACE_DIR = Path(__file__).resolve().parent.parent / "data" / "scale_free"

#: The shipped space's provenance, next to its files.
PROVENANCE_FILE = "PROVENANCE.json"

#: Tolerance of :func:`compare_ray_spaces`: |built - shipped| <= RTOL |shipped| + ATOL.
SHIPPED_RTOL = 1e-9
SHIPPED_ATOL_MM = 1e-12

#: Fields of a cause that change its rays (not its wording): what must agree for
#: a fresh build to be comparable with the shipped space.
_CAUSE_KEYS = ("keyword", "modulus", "neutral", "nodes", "scale")


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
        """JSON-able record for result files (``identification.json``, reports, studies)."""
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
    """
    base = Path(cwd) if cwd is not None else Path()
    if _has_space(base / WORKFLOW_SPACE_DIR):
        return base / WORKFLOW_SPACE_DIR if cwd is not None else Path(WORKFLOW_SPACE_DIR)
    return SHIPPED_SPACE_DIR


def shipped_provenance(folder=SHIPPED_SPACE_DIR) -> dict | None:
    """``PROVENANCE.json`` of a shipped space (None if the folder has none)."""
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
    other model file may be.
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
    return problems


# ------------------------------------------------------- does a build compare with it
def _normal(obj):
    from skinsuction.provenance import jsonable

    return json.loads(json.dumps(jsonable(obj), sort_keys=True))


def _cause_keys(causes: dict) -> dict:
    out = {}
    for name, c in (causes or {}).items():
        d = c.to_dict() if hasattr(c, "to_dict") else dict(c)
        out[name] = {k: d.get(k) for k in _CAUSE_KEYS}
    return _normal(out)


def _differing_keys(a, b, prefix="") -> list:
    if isinstance(a, dict) and isinstance(b, dict):
        keys = []
        for k in sorted(set(a) | set(b)):
            keys += _differing_keys(a.get(k), b.get(k), f"{prefix}{k}.")
        return keys
    return [] if a == b else [prefix.rstrip(".")]


def shipped_check_applies(spec, causes: dict, provenance: dict | None) -> tuple:
    """Whether a build of ``spec`` and ``causes`` is the space that was shipped: ``(bool, reason)``.

    It is when the effective ray specification (probes, ratio nodes, loads, X1d
    window and reference, bottom, mesh and fallbacks: what the workflow derives
    from the ``scale_free_space`` section and the study's ``mesh``) and the
    causes' rays (keyword, modulus, neutral, nodes, scale; not their wording)
    equal those recorded in ``PROVENANCE.json``.

    >>> from skinsuction.space import RaySpec
    >>> spec = RaySpec(probes_mm=[2, 6], ratio_nodes=[0.01, 0.1], load_max=100)
    >>> shipped_check_applies(spec, {}, {"ray_spec": spec.to_dict(), "causes": {}})
    (True, 'the configuration is the one the shipped space was built from')
    >>> ok, why = shipped_check_applies(spec, {}, {"ray_spec": {**spec.to_dict(), "load_max": 200},
    ...                                            "causes": {}})
    >>> ok, why.rsplit(": ", 1)[-1]
    (False, 'ray_spec.load_max')
    """
    if not provenance:
        return False, "no shipped space (no PROVENANCE.json)"
    spec_d = _normal(spec.to_dict() if hasattr(spec, "to_dict") else spec)
    keys = _differing_keys({"ray_spec": spec_d, "causes": _cause_keys(causes)},
                           {"ray_spec": _normal(provenance.get("ray_spec") or {}),
                            "causes": _cause_keys(provenance.get("causes") or {})})
    if keys:
        shown = ", ".join(keys[:8]) + (f" and {len(keys) - 8} more" if len(keys) > 8 else "")
        return False, ("the configuration's scale-free space differs from the one the shipped "
                       f"space was built from ({provenance.get('config_file') or 'a custom configuration'}): "
                       f"{shown}")
    return True, "the configuration is the one the shipped space was built from"


# ----------------------------------------------------------- ray-by-ray comparison
def _ray_arrays(space: RaySpace) -> dict:
    """``{ray_id: deflections}`` of a space, with its probe/ratio/coordinate axes checked."""
    out = {}
    for ray in rays_of(space.spec, space.cause):
        if not space.has_probe(ray["probe_mm"]):
            continue
        i = space.spec.ratio_nodes.index(ray["ratio"])
        j = 0 if space.cause is None else list(space.coordinates).index(ray["coordinate"])
        out[ray["ray_id"]] = space.rays(ray["probe_mm"])[i, j]
    return out


def compare_ray_spaces(built: RaySpace, shipped: RaySpace, rtol: float = SHIPPED_RTOL,
                       atol: float = SHIPPED_ATOL_MM) -> tuple:
    """Compare two spaces of one model ray by ray: ``(row, {ray_id: why})``.

    A ray agrees when both spaces hold it (same id: probe, X1h/X1d, cause
    coordinate), at the same pressures, with the same NaN pattern, and
    ``|built - shipped| <= rtol |shipped| + atol`` (mm) at every finite node.
    ``row``: ``model, rays_compared, rays_differing, max_abs_diff_mm,
    max_rel_diff`` (largest differences over the rays both hold).

    >>> import numpy as np
    >>> from skinsuction.space import RaySpace, RaySpec
    >>> spec = RaySpec(probes_mm=[2], ratio_nodes=[0.01, 0.1], load_max=100, load_steps=3)
    >>> a = RaySpace(None, spec, np.array([np.nan]), {2.0: np.ones((2, 1, 4))})
    >>> b = RaySpace(None, spec, np.array([np.nan]), {2.0: np.ones((2, 1, 4))})
    >>> b.deflection_mm[2.0][1, 0, 3] = np.nan
    >>> row, bad = compare_ray_spaces(a, b)
    >>> row["rays_compared"], row["rays_differing"], list(bad.values())
    (2, 1, ['NaN pattern differs: 1 nodes, the first at p/X1d = 100, NaN in the shipped space'])
    """
    name = shipped.name
    rows = {"model": name, "rays_compared": 0, "rays_differing": 0,
            "max_abs_diff_mm": 0.0, "max_rel_diff": 0.0}
    bad = {}
    if built.name != name:
        raise ValueError(f"comparing the {built.name} space with the {name} space")
    loads_b, loads_s = built.spec.load_nodes, shipped.spec.load_nodes
    same_p = loads_b.shape == loads_s.shape and np.allclose(loads_b, loads_s, rtol=1e-12)
    rb, rs = _ray_arrays(built), _ray_arrays(shipped)
    for rid in sorted(set(rs) - set(rb)):
        bad[rid] = "in the shipped space, not in the build"
    for rid in sorted(set(rb) - set(rs)):
        bad[rid] = "in the build, not in the shipped space"
    for rid in sorted(set(rb) & set(rs)):
        rows["rays_compared"] += 1
        a, b = rb[rid], rs[rid]
        if not same_p:
            bad[rid] = "loads p/X1d differ"
            continue
        fa, fb = np.isfinite(a), np.isfinite(b)
        both = fa & fb
        if both.any():
            d = np.abs(a[both] - b[both])
            rel = d / np.maximum(np.abs(b[both]), atol)
            rows["max_abs_diff_mm"] = max(rows["max_abs_diff_mm"], float(d.max()))
            rows["max_rel_diff"] = max(rows["max_rel_diff"], float(rel.max()))
        if not np.array_equal(fa, fb):
            k = int(np.flatnonzero(fa != fb)[0])
            side = "the build" if fb[k] else "the shipped space"
            bad[rid] = (f"NaN pattern differs: {int((fa != fb).sum())} nodes, the first at "
                        f"p/X1d = {loads_b[k]:.4g}, NaN in {side}")
        elif both.any() and not np.all(np.abs(a[both] - b[both]) <= rtol * np.abs(b[both]) + atol):
            d = np.abs(a[both] - b[both])
            k = int(np.argmax(d - rtol * np.abs(b[both])))
            bad[rid] = (f"deflections differ: largest {float(d.max()):.3g} mm "
                        f"(relative {float((d / np.maximum(np.abs(b[both]), atol)).max()):.3g}; "
                        f"at p/X1d = {loads_b[both][k]:.4g})")
    rows["rays_differing"] = len(bad)
    return rows, bad


class ShippedSpaceMismatch(RuntimeError):
    """A fresh build of the default space differs from the space shipped with skinsuction."""


def knife_edge_rays(*spaces) -> set:
    """Rays whose end depends on the solver's path, in any of ``spaces``: a fallback
    element carries part of them, or they stop before their last load.

    Where the default element stops, and so where a fallback's tail is spliced on,
    moves with round-off (the same solver on FElupe's assembly and on the fast one,
    equal to 1e-13, stops at different loads there): such a ray can differ between
    two machines while every ray the default element carries to the end agrees to
    round-off.

    >>> from types import SimpleNamespace as S
    >>> a = S(metadata={"rays": {"r1": {"mesh_fallback": 1, "converged": True},
    ...                          "r2": {"mesh_fallback": 0, "converged": True}}})
    >>> b = S(metadata={"rays": {"r2": {"mesh_fallback": 0, "converged": False}}})
    >>> sorted(knife_edge_rays(a, b))
    ['r1', 'r2']
    """
    out = set()
    for space in spaces:
        for rid, info in ((space.metadata or {}).get("rays") or {}).items():
            if int(info.get("mesh_fallback") or 0) > 0 or not info.get("converged", True):
                out.add(rid)
    return out


def check_shipped_space(built_dir, out_csv, spec, causes: dict, shipped_dir=SHIPPED_SPACE_DIR,
                        rtol: float = SHIPPED_RTOL, atol: float = SHIPPED_ATOL_MM) -> pd.DataFrame:
    """Compare the workflow's build of the scale-free space with the shipped one; write a table.

    When the configuration (``spec``, ``causes``) is the one the shipped space was
    built from (:func:`shipped_check_applies`), every model file of the shipped
    space is compared with the build's, ray by ray (:func:`compare_ray_spaces`),
    and ``out_csv`` gets one row per model: ``model, status`` (``equal``,
    ``knife_edge_moved`` or ``differs``), ``rays_compared, rays_differing,
    max_abs_diff_mm, max_rel_diff, rtol, atol_mm, differing_rays`` (the first 20
    ids), ``knife_edge_rays`` (how many of the differing rays are
    :func:`knife_edge_rays`), ``note``.  Otherwise the table has one row, status
    ``not_applicable``, saying why.

    A differing ray that a fallback carries or that stops early, in either space,
    is logged as a warning and counted (``knife_edge_moved``); any other differing
    ray fails the check.

    Raises
    ------
    ShippedSpaceMismatch
        Naming the rays that differ and are not knife-edge rays (after writing the
        table and logging every differing ray), so that a workflow run fails loudly.
    """
    shipped_dir = Path(shipped_dir)
    prov = shipped_provenance(shipped_dir)
    applies, reason = shipped_check_applies(spec, causes, prov)
    cols = ["model", "status", "rays_compared", "rays_differing", "max_abs_diff_mm",
            "max_rel_diff", "rtol", "atol_mm", "differing_rays", "knife_edge_rays", "note"]
    if not applies:
        log.info("check of the shipped space does not apply: %s", reason)
        table = pd.DataFrame([{"model": "", "status": "not_applicable", "rays_compared": 0,
                               "rays_differing": 0, "max_abs_diff_mm": math.nan,
                               "max_rel_diff": math.nan, "rtol": rtol, "atol_mm": atol,
                               "differing_rays": "", "knife_edge_rays": 0, "note": reason}],
                             columns=cols)
        write_table(table, out_csv)
        return table
    problems = verify_shipped_files(shipped_dir)
    if problems:
        raise ShippedSpaceMismatch(f"{shipped_dir}: the shipped files disagree with their "
                                   f"{PROVENANCE_FILE}: " + "; ".join(problems))
    rows, all_bad = [], {}
    for name in sorted(prov["files"], key=lambda n: (n != f"{BASELINE}.parquet", n)):
        shipped = read_ray_space(shipped_dir / name)
        built_path = Path(built_dir) / name
        if not built_path.is_file():
            raise ShippedSpaceMismatch(f"{built_path}: not built, but shipped ({name})")
        built = read_ray_space(built_path)
        row, bad = compare_ray_spaces(built, shipped, rtol, atol)
        ids = sorted(bad)
        edge = knife_edge_rays(built, shipped) & set(ids)
        status = "equal" if not bad else ("knife_edge_moved" if edge == set(ids) else "differs")
        rows.append({**row, "status": status, "rtol": rtol, "atol_mm": atol,
                     "differing_rays": ";".join(ids[:20]) + (f";... {len(ids) - 20} more"
                                                             if len(ids) > 20 else ""),
                     "knife_edge_rays": len(edge), "note": reason})
        for rid in ids:
            if rid in edge:
                log.warning("%s: ray %s (a fallback carries it or it stops early: where, "
                            "moves with round-off): %s", name, rid, bad[rid])
            else:
                log.error("%s: ray %s: %s", name, rid, bad[rid])
        all_bad.update({f"{shipped.name}: {rid}": why for rid, why in bad.items()
                        if rid not in edge})
        log.info("%s: %d rays compared, %d differ (largest difference %.3g mm, relative %.3g)",
                 name, row["rays_compared"], row["rays_differing"], row["max_abs_diff_mm"],
                 row["max_rel_diff"])
    table = pd.DataFrame(rows, columns=cols)
    write_table(table, out_csv)
    log.info("shipped space check:\n%s", table.drop(columns=["note"]).to_string(index=False))
    if all_bad:
        shown = "; ".join(f"{rid} ({why})" for rid, why in list(all_bad.items())[:10])
        more = f"; and {len(all_bad) - 10} more (see the log)" if len(all_bad) > 10 else ""
        raise ShippedSpaceMismatch(
            f"the fresh build in {built_dir} differs from the default space shipped with "
            f"skinsuction ({shipped_dir}) in {len(all_bad)} rays the default element carries to "
            f"the end (tolerance {rtol:g} relative + {atol:g} mm): {shown}{more}. If the FE code changed on purpose, ship the new "
            "build: `snakemake --cores 2 ship_scale_free_space`")
    return table


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

    Returns the provenance record.
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
