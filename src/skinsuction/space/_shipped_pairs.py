"""The pair spaces of the default space: which go with a space, and shipping them.

Pair spaces (:mod:`._pairs`) live in the ``pairs/`` folder of a scale-free space;
the package ships the default's with their own ``PROVENANCE.json``
(:func:`ship_pair_spaces`, checked by :func:`skinsuction.space.verify_shipped_files`).
"""

from __future__ import annotations

import datetime as _dt
import json
import logging
from pathlib import Path

from skinsuction._files import atomic_output, file_sha256

from ._causes import BASELINE
from ._pairs import PAIRS_FOLDER, read_pair_space, read_pair_spaces
from ._ray_space import read_ray_space
from ._rays import RaySpec
from ._shipped import PROVENANCE_FILE, SHIPPED_SPACE_DIR, _normal

log = logging.getLogger(__name__)

__all__ = ["pairs_for", "ship_pair_spaces"]


def pairs_for(space_dir, spec: RaySpec) -> dict:
    """The pair spaces that go with a scale-free space of this specification.

    Those of ``space_dir``'s ``pairs/`` folder, else those shipped with the package
    (a workflow build of the single causes that did not build the pairs, target
    ``scale_free_pairs``); only pairs built with the same ray specification, or,
    where there are none, with the same rays up to the start of its load tail
    (pairs built before the tail: the diagnosis tries them only within their reach).

    Parameters
    ----------
    space_dir : path-like or None
    spec : RaySpec
        The single spaces' specification.

    Returns
    -------
    dict
        ``{name: PairRaySpace}``, possibly empty.
    """
    for folder in ([Path(space_dir)] if space_dir is not None else []) + [SHIPPED_SPACE_DIR]:
        pairs = read_pair_spaces(folder)
        for want in (spec, spec.untailed()):
            found = {n: s for n, s in pairs.items() if s.spec.to_dict() == want.to_dict()}
            if found:
                return found
    return {}


def ship_pair_spaces(built_dir, dest=SHIPPED_SPACE_DIR, *, build_command: str | None = None,
                     repo=None) -> dict:
    """Copy the built pair spaces (``<built_dir>/pairs/*.parquet``) into ``dest/pairs``.

    Their ``PROVENANCE.json`` records each file (SHA-256, rows, rays), the pairs,
    the ray specification and the commits they were built and shipped from.  The
    pairs must share the specification of the single spaces shipped in ``dest``.

    Parameters
    ----------
    built_dir : path-like
        The scale-free space's folder (its ``pairs/`` subfolder is shipped).
    dest : path-like
        The shipped space's folder (default: the package's).
    build_command : str, optional
        The command that built them, for the record.
    repo : path-like, optional
        The git repository whose commit is recorded.

    Returns
    -------
    dict
        The provenance record written.

    Raises
    ------
    FileNotFoundError, ValueError
        No pair built, or one of another ray specification than the shipped space.
    """
    from skinsuction import __version__
    from skinsuction.provenance import git_info, jsonable

    src, out = Path(built_dir) / PAIRS_FOLDER, Path(dest) / PAIRS_FOLDER
    files = sorted(src.glob("*.parquet"))
    if not files:
        raise FileNotFoundError(f"{src}: no pair spaces to ship (build them first: "
                                "`snakemake --cores 2 scale_free_pairs`)")
    base = read_ray_space(Path(dest) / f"{BASELINE}.parquet")
    pairs = {p.name: read_pair_space(p) for p in files}
    for name, s in pairs.items():
        if _normal(s.spec.to_dict()) != _normal(base.spec.to_dict()):
            raise ValueError(f"{src / name}: its ray specification differs from the shipped "
                             f"{BASELINE}.parquet's (ship the single spaces first)")
    out.mkdir(parents=True, exist_ok=True)
    written = {}
    for s in pairs.values():
        for probe in s.probes_mm:
            name = f"{s.name}__p{probe:g}.parquet"
            _write_probe(s, probe, out / name)
            written[name] = s
    for stale in out.glob("*.parquet"):
        if stale.name not in written:
            stale.unlink()
    git = git_info(repo)
    record = jsonable({
        "what": "the pair spaces of skinsuction's default scale-free space: two causes at "
                "once, every node of the first times the listed nodes of the second; read by "
                "diagnose and study for the second effect of a ramp",
        "skinsuction_version": __version__,
        "shipped_from_commit": git.get("commit"), "shipped_from_dirty": git.get("dirty"),
        "shipped_utc": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "build_command": build_command,
        "ray_spec": base.spec.to_dict(),
        "files": {name: {"sha256": file_sha256(out / name),
                         "bytes": (out / name).stat().st_size,
                         "pair": s.pair.to_dict(),
                         "built_at_commit": (s.metadata.get("git") or {}).get("commit"),
                         "created_utc": s.metadata.get("created_utc"),
                         "new_rays_all_probes": int(s.metadata.get("n_rays", 0)),
                         "stopped_early_all_probes": int(s.metadata.get("n_stopped", 0))}
                  for name, s in written.items()},
    })
    with atomic_output(out / PROVENANCE_FILE) as tmp:
        tmp.write_text(json.dumps(record, indent=1) + "\n", encoding="utf-8")
    log.info("shipped %d pair spaces (%d files) from %s to %s", len(files), len(written), src,
             out)
    return record


#: What the shipped copy keeps of each ray's solver record (the rest, e.g. the skin of
#: its curve, repeats the ray id).
SOLVER_KEYS = ("converged", "mesh_fallback", "last_converged_mbar", "reason", "seconds")


def _write_probe(space, probe: float, path: Path) -> None:
    """One probe's rays of a pair space, its solver records cut to :data:`SOLVER_KEYS`:
    a file per probe keeps the shipped files small (read back together by
    :func:`skinsuction.space.read_pair_spaces`)."""
    from ._pairs import PairRaySpace
    from ._storage import _write_parquet

    one = PairRaySpace(space.cause, space.spec, space.coordinates,
                       {probe: space.rays(probe)}, {}, second=space.second)
    tag = f"p{probe:g}_"
    meta = {**{k: v for k, v in space.metadata.items() if k != "rays"},
            "rays": {rid: {k: rec.get(k) for k in SOLVER_KEYS}
                     for rid, rec in space.metadata.get("rays", {}).items()
                     if rid.startswith(tag)}}
    _write_parquet(one.frame(), path, meta)  # atomic
