"""Neo-Hookean (and cause) rays at a measurement's own geometry, solved on demand.

The scale-free space holds rays of the Cutometer probes (2, 4, 6 and 8 mm) for
the paper's layers (dermis and hypodermis 1 mm each).  A measurement with another
aperture, or with its own layer thicknesses (ultrasound, OCT), gets its rays
solved at exactly that geometry, with the space's ray specification
(:class:`OnDemandRays`), and cached on disk: 16 FE rays per probe, about 10-20 s
of CPU, once per geometry.  Interpolating a precomputed grid over the geometry
instead was measured and rejected (docs/geometry.md; :mod:`._geometry`).

Geometric similarity, M(s a, s t_d, s t_h) = s M(a, t_d, t_h) (tested to
round-off in tests/test_model.py), makes a cached set of rays serve every
geometrically similar measurement: the cache key is the dimensionless geometry
(t_d/a, t_h/a), the rays are scaled by the aperture.  The cache folder is named
by the ray specification and a hash of the FE code, so a change of either
solves the rays again.
"""

from __future__ import annotations

import hashlib
import logging
import os
from pathlib import Path

import numpy as np

log = logging.getLogger(__name__)

__all__ = ["OnDemandRays", "default_cache_dir"]


def default_cache_dir() -> Path:
    """Where on-demand rays are kept.

    Returns
    -------
    Path
        ``$SKINSUCTION_CACHE``, else ``$XDG_CACHE_HOME/skinsuction``, else
        ``~/.cache/skinsuction``.
    """
    env = os.environ.get("SKINSUCTION_CACHE")
    if env:
        return Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "skinsuction"


def _fe_code_hash() -> str:
    """Hash of the FE model's and the ray solve's source: a change invalidates the cache."""
    root = Path(__file__).resolve().parents[1]
    files = sorted((root / "model").glob("*.py")) + [
        root / "space" / n for n in ("_solve.py", "_ray_solve.py", "_rays.py", "_storage.py")]
    h = hashlib.sha256()
    for f in files:
        h.update(f.name.encode())
        h.update(f.read_bytes())
    return h.hexdigest()[:16]


class OnDemandRays:
    """Neo-Hookean rays of one probe at one geometry, solved when first needed, cached.

    Parameters
    ----------
    spec : RaySpec
        The ray specification of the space they extend (ratio nodes, loads, mesh,
        fallbacks): the rays are those the workflow would have run.
    cache_dir : path-like, optional
        Default :func:`default_cache_dir`; a subfolder per specification and FE code.
    workers : int
        Processes that solve the rays of one geometry.
    progress : text stream or None
        Where each solve is announced, with its time (default stderr): a
        geometry's rays of every cause take minutes, and the user must see why.
    """

    def __init__(self, spec, cache_dir=None, workers: int = 1, progress="stderr"):
        import json
        import sys

        self.spec = spec
        self.workers = max(1, int(workers))
        self.progress = sys.stderr if progress == "stderr" else progress
        key = hashlib.sha256(json.dumps(spec.to_dict(), sort_keys=True).encode()
                             + _fe_code_hash().encode()).hexdigest()[:16]
        self.dir = Path(cache_dir or default_cache_dir()) / "rays" / key
        self.solved = 0  # geometries solved by this object (not read from the cache)

    def _ray_ids(self, probe_mm, t_d, t_h, cause=None, coordinate=None, ratio_nodes=None):
        from ._rays import ray_id
        from ._storage import round_sig

        x1d = self.spec.x1d_ref
        out = []
        for r in self.spec.ratio_nodes if ratio_nodes is None else ratio_nodes:
            params = {"probe_mm": probe_mm, "bottom": self.spec.bottom,
                      "x1d": round_sig(x1d), "x1h": round_sig(r * x1d),
                      "t_d": t_d, "t_h": t_h}
            if cause is not None:
                params.update({k: round_sig(v, 6) for k, v in
                               cause.simulate_keywords(coordinate, x1d).items()})
            out.append(ray_id(params))
        return out

    def rays(self, probe_mm: float, t_d: float, t_h: float, cause=None, ratio_nodes=None):
        """``(rays (n_r, n_c, n_p) in mm, info)`` of one probe at one geometry.

        ``cause=None``: the neo-Hookean rays (``n_c = 1``); a :class:`Cause`: its
        rays at every one of its nodes (the neutral node is the neo-Hookean ray).
        A thickness cause (``t_d``, ``t_h``) replaces that layer's thickness.
        The rays are solved for the reference aperture of the dimensionless
        geometry (2 mm, thicknesses ``t/a``) and scaled by ``a`` (geometric
        similarity), so similar measurements share them.  ``ratio_nodes``: only
        these X1h/X1d nodes of the specification (``n_r`` of them; default all);
        the rays of other nodes solved later join the same cache file.
        """
        from ._storage import round_sig

        nodes = self.spec.ratio_nodes if ratio_nodes is None else tuple(ratio_nodes)
        if not set(nodes) <= set(self.spec.ratio_nodes):
            raise ValueError(f"ratio nodes {nodes} are not nodes of the ray specification "
                             f"{self.spec.ratio_nodes}")
        a = probe_mm / 2
        ref_td, ref_th = round_sig(t_d / a, 6), round_sig(t_h / a, 6)
        if cause is None:
            return self._read(ref_td, ref_th, a, None, None, nodes)
        columns, infos = [], []
        for c in cause.nodes:
            if c == cause.neutral:
                m, info = self._read(ref_td, ref_th, a, None, None, nodes)
            else:
                m, info = self._read(ref_td, ref_th, a, cause, c, nodes)
            columns.append(m[:, 0])
            infos.append(info)
        info = {"cache": str(self.dir), "rays": sum(i["rays"] for i in infos),
                "stopped_early": sum(i["stopped_early"] for i in infos)}
        return np.stack(columns, axis=1), info

    def _read(self, ref_td, ref_th, a, cause, c, nodes):
        from ._storage import _read_parquet, round_sig

        if cause is None:
            path = self.dir / f"td{ref_td:g}_th{ref_th:g}.parquet"
            coord = None
        else:
            # a thickness node is a length: it scales with the aperture like the layers
            coord = round_sig(c / a, 6) if cause.geometric else c
            path = self.dir / f"td{ref_td:g}_th{ref_th:g}__{cause.keyword}{coord:g}.parquet"
        ids = self._ray_ids(2.0, ref_td, ref_th, cause, coord, nodes)
        if not path.exists():
            self._solve(path, ids, ref_td, ref_th)
        frame, meta = _read_parquet(path)
        solved = set(frame["ray_id"])
        missing = [rid for rid in ids if rid not in solved]
        if missing:  # other X1h/X1d nodes than those solved before: add them to the file
            extra = path.with_name(f"{path.stem}.extra.parquet")
            self._solve(extra, missing, ref_td, ref_th)
            _merge_bundles([path, extra], path)
            frame, meta = _read_parquet(path)
        p = np.asarray(self.spec.pressures_mbar)
        out = np.full((len(ids), 1, p.size), np.nan)
        for i, rid in enumerate(ids):
            g = frame[frame["ray_id"] == rid]
            if len(g) != p.size:
                raise RuntimeError(f"{path}: ray {rid} is missing or incomplete; delete the "
                                   "file to solve it again")
            out[i, 0] = g["deflection_mm"].to_numpy(float) * a
        infos = meta.get("rays") or {}
        stopped = sum(1 for rid in ids if not infos.get(rid, {}).get("converged", True))
        return out, {"cache": str(path), "rays": len(ids), "stopped_early": stopped}

    def _solve(self, path: Path, ids, td: float, th: float):
        from ._ray_solve import compute_bundle

        import time

        log.info("solving %d FE rays on demand for t_d/a = %g, t_h/a = %g -> %s",
                 len(ids), td, th, path)
        start = time.perf_counter()
        path.parent.mkdir(parents=True, exist_ok=True)
        args = (self.spec.pressures_mbar, self.spec.mesh, list(self.spec.fallback))
        if self.workers > 1:
            from concurrent.futures import ProcessPoolExecutor

            parts = [ids[i::self.workers] for i in range(self.workers)]
            tmp = [path.with_name(f"{path.stem}.part{i}.parquet") for i in range(len(parts))]
            with ProcessPoolExecutor(self.workers) as pool:
                list(pool.map(compute_bundle, parts, tmp, *[[a] * len(parts) for a in args]))
            _merge_bundles(tmp, path)
        else:
            compute_bundle(ids, path, *args)
        self.solved += 1
        if self.progress is not None:
            print(f"solved on demand: {len(ids)} FE rays for t_d/a = {td:g}, t_h/a = {th:g} "
                  f"({path.stem}) in {time.perf_counter() - start:.0f} s; cached in {path.parent}",
                  file=self.progress, flush=True)


def _merge_bundles(parts, path):
    import pandas as pd

    from ._storage import _read_parquet, _write_parquet

    frames, meta = [], {}
    for p in parts:
        f, m = _read_parquet(p)
        frames.append(f)
        rays = {**meta.get("rays", {}), **m.get("rays", {})}
        meta = {**m, "rays": rays}
    _write_parquet(pd.concat(frames, ignore_index=True), path, meta)
    for p in parts:
        if Path(p) != Path(path):
            Path(p).unlink(missing_ok=True)
