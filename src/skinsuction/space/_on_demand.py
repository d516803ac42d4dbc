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
import math
import os
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from ._coordinates import LAYER_PATHS, similar_length
from ._rays import _ray_params, ray_id
from ._storage import AXIS_PATHS, _read_parquet, _write_parquet, round_sig

log = logging.getLogger(__name__)

__all__ = ["OnDemandRays", "default_cache_dir", "layer_thicknesses", "LAYER_PATHS"]

#: The ray-id keyword (a grid axis) of each layer path.
_LAYER_KEYWORDS = {AXIS_PATHS[key]: key for key in ("t_d", "t_h")}


def layer_thicknesses(layers) -> dict:
    """The layer thicknesses rays are solved for, by parameter path.

    Parameters
    ----------
    layers : Skin or mapping
        A dermis over a hypodermis (:class:`skinsuction.model.Skin`; only its
        thicknesses are read), or ``{"dermis.thickness": mm,
        "hypodermis.thickness": mm}``.

    Returns
    -------
    dict
        ``{"dermis.thickness": mm, "hypodermis.thickness": mm}`` (floats).

    Raises
    ------
    ValueError
        For another stack of layers, a missing or unknown path, or a thickness
        that is not a positive number.

    Examples
    --------
    >>> layer_thicknesses({"dermis.thickness": 1.3, "hypodermis.thickness": 3})
    {'dermis.thickness': 1.3, 'hypodermis.thickness': 3.0}
    """
    if isinstance(layers, Mapping):
        unknown = sorted(set(layers) - set(LAYER_PATHS))
        missing = [p for p in LAYER_PATHS if p not in layers]
        if unknown or missing:
            raise ValueError(f"the layers of rays are {list(LAYER_PATHS)}; "
                             f"missing {missing}, unknown {unknown}")
        out = {path: float(layers[path]) for path in LAYER_PATHS}
    else:
        names = tuple(getattr(layers, "names", ()))
        if names != ("dermis", "hypodermis"):
            raise ValueError(f"rays are solved for a dermis over a hypodermis, not the "
                             f"layers {list(names) or layers!r}")
        out = {path: float(layers.get(path)) for path in LAYER_PATHS}
    for path, value in out.items():
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{path} must be a positive number of mm, not {value!r}")
    return out


def _keywords(layers: dict) -> dict:
    """``{"t_d": mm, "t_h": mm}``: the ray-id keywords of layers by path."""
    return {_LAYER_KEYWORDS[path]: value for path, value in layers.items()}


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
        fallbacks): the rays are those the workflow would have run, without its
        load tail (:meth:`RaySpec.untailed`, as the geometry spaces).
    cache_dir : path-like, optional
        Default :func:`default_cache_dir`; a subfolder per specification and FE code.
    workers : int
        Processes that solve the rays of one geometry.
    progress : text stream or None
        Where each solve is announced, with its time (default stderr): a
        geometry's rays of every cause take minutes, and the user must see why.
    geometry : "auto", GeometrySpace, path-like or None
        Where the neo-Hookean rays (and a thickness cause's) are read first, by
        interpolation over the geometry (:class:`GeometrySpace`), before any is
        solved.  "auto" (default): the workflow's build in the working directory,
        else the one shipped with the package, if it was solved with the same rays
        as ``spec`` (:func:`same_rays`).  None: every ray is solved.  The other
        causes' rays are read off their own geometry spaces where these lie beside
        it (``<cause>.parquet``, :func:`cause_geometry_space`) or are given in
        ``cause_geometry``.
    tolerance : float
        A ray read off the geometry space whose error estimate (the spread of log
        M over shifted stencils, :meth:`GeometrySpace.rays`) exceeds this is solved
        instead: the grid is exact at its nodes and smooth between them except
        where a soft hypodermis lets a thin dermis bulge towards its limit load.
    cause_geometry : dict name -> GeometrySpace, optional
        A cause's geometry space, in place of the one beside ``geometry``'s file.
    """

    def __init__(self, spec, cache_dir=None, workers: int = 1, progress="stderr",
                 geometry="auto", tolerance: float = 1e-2, cause_geometry=None):
        import json
        import sys

        # a subject's rays stop where the load tail starts, as the geometry spaces'
        # do: at_bound (edge coverage) says so where a fit needs more
        spec = spec.untailed()
        self.spec = spec
        self.workers = max(1, int(workers))
        self.progress = sys.stderr if progress == "stderr" else progress
        key = hashlib.sha256(json.dumps(spec.to_dict(), sort_keys=True).encode()
                             + _fe_code_hash().encode()).hexdigest()[:16]
        self.dir = Path(cache_dir or default_cache_dir()) / "rays" / key
        self.solved = 0  # geometries solved by this object (not read from the cache)
        self.geometry = _geometry_space(geometry, spec)
        self.interpolated = 0  # ray sets read off the geometry space
        self.tolerance = float(tolerance)
        self._cause_spaces = dict(cause_geometry or {}) if self.geometry is not None else {}
        #: :meth:`moved_rays` reads a change of layers off the geometry spaces where the
        #: error estimates of both reads are within this (else it solves, as :meth:`rays`)
        self.move_tolerance = 5 * self.tolerance

    def _ray_ids(self, probe_mm, layers, cause=None, coordinate=None, ratio_nodes=None):
        """The ids of the rays at ``layers`` (by path), one per X1h/X1d node."""
        nodes = self.spec.ratio_nodes if ratio_nodes is None else ratio_nodes
        return [ray_id(_ray_params(self.spec, probe_mm, r, cause, coordinate,
                                   _keywords(layers), digits=6)) for r in nodes]

    def rays(self, probe_mm: float, layers, cause=None, ratio_nodes=None,
             reads_up_to_mm: float | None = None):
        """The rays of one probe at one geometry.

        The rays are solved for the reference aperture of the dimensionless
        geometry (2 mm, thicknesses ``t/a``) and scaled by ``a`` (geometric
        similarity), so similar measurements share them.

        Parameters
        ----------
        probe_mm : float
            Aperture diameter ``2 a`` (mm).
        layers : Skin or mapping
            The layers: a dermis over a hypodermis (only its thicknesses are read),
            or ``{"dermis.thickness": mm, "hypodermis.thickness": mm}``
            (:func:`layer_thicknesses`).
        cause : Cause, optional
            None: the neo-Hookean rays (``n_c = 1``); a cause: its rays at every
            one of its nodes (the neutral node is the neo-Hookean ray).  A
            thickness cause replaces that layer's thickness.
        ratio_nodes : sequence of float, optional
            Only these X1h/X1d nodes of the specification (``n_r`` of them;
            default all); the rays of other nodes solved later join the same
            cache file.
        reads_up_to_mm : float, optional
            The largest deflection a fit of the measurement can read (mm): a ray
            read off a geometry space is solved only where its error estimate
            exceeds the tolerance at deflections up to it (default: anywhere).  A
            ray runs on to the dome's limit load, where the grid's nodes splice onto
            their fallbacks at different loads; a measurement that reads the first
            third of it need not pay for that.

        Returns
        -------
        rays : ndarray, shape (n_r, n_c, n_p)
            Deflections (mm) at the specification's pressures.
        info : dict
            ``cache`` (where they are kept), ``rays`` (how many), ``stopped_early``.
        """
        nodes = self.spec.ratio_nodes if ratio_nodes is None else tuple(ratio_nodes)
        if not set(nodes) <= set(self.spec.ratio_nodes):
            raise ValueError(f"ratio nodes {nodes} are not nodes of the ray specification "
                             f"{self.spec.ratio_nodes}")
        a = probe_mm / 2
        ref = {path: round_sig(similar_length(t, probe_mm), 6)
               for path, t in layer_thicknesses(layers).items()}
        if cause is None:
            return self._read(ref, a, None, None, nodes, reads_up_to_mm)
        columns, infos = [], []
        for c in cause.nodes:
            if c == cause.neutral:
                m, info = self._read(ref, a, None, None, nodes, reads_up_to_mm)
            else:
                m, info = self._read(ref, a, cause, c, nodes, reads_up_to_mm)
            columns.append(m[:, 0])
            infos.append(info)
        info = {"cache": str(self.dir), **{k: sum(i.get(k, 0) for i in infos) for k in (
            "rays", "stopped_early", "rays_interpolated", "rays_solved")}}
        return np.stack(columns, axis=1), info

    def moved_rays(self, probe_mm: float, layers, other, center, cause=None, ratio_nodes=None,
                   reads_up_to_mm: float | None = None):
        """The rays at the layers ``other``: ``center`` (the rays at ``layers``) moved by
        the change the geometry spaces read between the two layers.

        A thickness bracket of the nuisance (:class:`ThicknessNuisance`) moves with the
        thickness by the curve's change over 0.1 mm, not by its level: the
        interpolation errors of two geometries a bracket apart nearly cancel in their
        ratio (on one subject's 132 FE-solved pairs of strain-stiffening rays, rays off
        by up to 0.95 % changed within 0.002 % of FE in the median and 0.98 % at most,
        3 % of the change in the median: ``docs/geometry.md``). So a bracket is read
        wherever both geometries lie in the grid with error estimates within
        :attr:`move_tolerance`, and its rays keep the centre's source (read or solved).
        Elsewhere it is :meth:`rays` at ``other``.

        Parameters
        ----------
        probe_mm : float
        layers, other : Skin or mapping
            The centre's layers and the bracket's (:func:`layer_thicknesses`).
        center : ndarray, shape (n_r, n_c, n_p)
            The rays at ``layers``, at this solver's pressures.
        cause, ratio_nodes, reads_up_to_mm
            As :meth:`rays`.

        Returns
        -------
        rays : ndarray, shape (n_r, n_c, n_p)
        info : dict
            As :meth:`rays`; ``cache`` is "geometry space (moved)" for a read move.
        """
        center = np.asarray(center, dtype=float)
        reads = [self.read_rays(probe_mm, g, cause, ratio_nodes, reads_up_to_mm)
                 for g in (layers, other)]
        if (any(r is None for r in reads) or max(r[1] for r in reads) > self.move_tolerance
                or reads[0][0].shape != center.shape):
            return self.rays(probe_mm, other, cause, ratio_nodes, reads_up_to_mm)
        with np.errstate(divide="ignore", invalid="ignore"):
            moved = center * (reads[1][0] / reads[0][0])
        moved[..., np.asarray(self.spec.pressures_mbar) == 0.0] = 0.0
        n = moved.shape[0] * moved.shape[1]
        return moved, {"cache": "geometry space (moved)", "rays": n, "rays_interpolated": n,
                       "rays_solved": 0, "stopped_early": int(np.isnan(moved[:, :, -1]).sum())}

    def read_rays(self, probe_mm: float, layers, cause=None, ratio_nodes=None,
                  reads_up_to_mm: float | None = None):
        """The rays read off the geometry spaces whatever their error estimate, and the
        largest estimate: ``(rays (n_r, n_c, n_p), estimate)``, or None where a space
        does not hold them (no space of the cause, outside its grid)."""
        nodes = self.spec.ratio_nodes if ratio_nodes is None else tuple(ratio_nodes)
        a = probe_mm / 2
        ref = {path: round_sig(similar_length(t, probe_mm), 6)
               for path, t in layer_thicknesses(layers).items()}
        columns, estimate = [], 0.0
        for c in [None] if cause is None else cause.nodes:
            neutral = cause is None or c == cause.neutral
            found = self._from_geometry(ref, a, None if neutral else cause,
                                        None if neutral else c, nodes, reads_up_to_mm)
            if found is None:
                return None
            columns.append(found[0][:, 0])
            estimate = max(estimate, float(np.max(found[1]["error_estimate"])))
        return np.stack(columns, axis=1), estimate

    def _from_geometry(self, ref, a, cause, c, nodes, cap=None):
        """The rays at ``ref`` (scaled by ``a``) read off the geometry space, and the
        nodes whose error estimate exceeds the tolerance (to be solved); None where
        the spaces do not hold them (no space of that cause, outside its grid)."""
        if self.geometry is None:
            return None
        layers, space, coordinate = _keywords(ref), self.geometry, None
        if cause is not None and cause.geometric:
            layers[cause.keyword] = round_sig(similar_length(c, 2 * a), 6)
        elif cause is not None:
            space, coordinate = self.cause_geometry(cause), c
            if space is None:
                return None
        if not space.grid.covers(layers["t_d"], layers["t_h"]):
            return None
        m, info = space.rays(2.0, layers["t_d"], layers["t_h"], nodes, coordinate,
                             deflection_cap=None if cap is None else cap / a)
        self.interpolated += 1
        return m * a, info

    def holds(self, probe_mm: float, layers) -> bool:
        """Whether the neo-Hookean geometry space's grid holds ``layers`` under this probe
        (its rays are read there, not solved whole; :meth:`reading_only` reads them
        whatever their error estimate)."""
        if self.geometry is None:
            return False
        ref = _keywords({path: round_sig(similar_length(t, probe_mm), 6)
                         for path, t in layer_thicknesses(layers).items()})
        return bool(self.geometry.grid.covers(ref["t_d"], ref["t_h"]))

    def reading_only(self) -> "OnDemandRays":
        """This solver reading every ray the geometry spaces hold whatever its error
        estimate (no tolerance), sharing its cache: for fits that only sample a
        likelihood's tail, where a ray solved for accuracy would cost more than the
        fit is worth."""
        import copy

        out = copy.copy(self)
        out.tolerance = out.move_tolerance = math.inf
        return out

    def cause_geometry(self, cause):
        """The geometry space of a cause (not a thickness), or None where there is none."""
        if cause.name not in self._cause_spaces:
            from ._geometry_space import cause_geometry_space

            self._cause_spaces[cause.name] = cause_geometry_space(self.geometry, cause,
                                                                  self.spec)
        return self._cause_spaces[cause.name]

    def _read(self, ref, a, cause, c, nodes, cap=None):
        """The rays at the reference layers ``ref`` (2 mm aperture) scaled by ``a``: read
        off the geometry space where its error estimate is within the tolerance, else
        from the cache file, the missing ones solved into it first."""
        found = self._from_geometry(ref, a, cause, c, nodes, cap)
        if found is None:
            return self._read_cache(ref, a, cause, c, nodes)
        m, info = found
        est = info.pop("error_estimate")
        uncertain = [k for k, e in enumerate(est) if not e <= self.tolerance]
        info.update(cache="geometry space", rays_interpolated=len(nodes) - len(uncertain),
                    rays_solved=len(uncertain), largest_error_estimate=float(np.max(est)))
        if uncertain:
            self._settle(ref, a, cause, c, [nodes[k] for k in uncertain], m, uncertain, info)
        return m, info

    def _settle(self, ref, a, cause, c, nodes, m, rows, info):
        """The rays ``nodes`` read with an error estimate over the tolerance (rows ``rows``
        of ``m``, in place): from the cache, solved first where missing."""
        solved, sinfo = self._read_cache(ref, a, cause, c, nodes)
        m[rows] = solved
        info.update(cache=sinfo["cache"], stopped_early=int(np.isnan(m[:, 0, -1]).sum()))

    def _read_cache(self, ref, a, cause, c, nodes, solve: bool = True):
        """The rays at ``ref`` scaled by ``a`` from the cache file, solved first if missing
        (``solve=False``: None where any is missing)."""
        stem = "td{t_d:g}_th{t_h:g}".format(**_keywords(ref))
        if cause is None:
            path = self.dir / f"{stem}.parquet"
            coord = None
        else:
            # a thickness node is a length: it scales with the aperture like the layers
            coord = round_sig(similar_length(c, 2 * a), 6) if cause.geometric else c
            path = self.dir / f"{stem}__{cause.keyword}{coord:g}.parquet"
        ids = self._ray_ids(2.0, ref, cause, coord, nodes)
        if not path.exists():
            if not solve:
                return None
            self._solve(path, ids, ref)
        frame, meta = _read_parquet(path)
        solved = set(frame["ray_id"])
        missing = [rid for rid in ids if rid not in solved]
        if missing and not solve:
            return None
        if missing:  # other X1h/X1d nodes than those solved before: add them to the file
            extra = path.with_name(f"{path.stem}.extra.parquet")
            self._solve(extra, missing, ref)
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

    def _solve(self, path: Path, ids, ref: dict):
        """Solve the rays ``ids`` at the reference layers ``ref`` into the file ``path``."""
        import time

        from ._ray_solve import compute_bundle

        td, th = _keywords(ref)["t_d"], _keywords(ref)["t_h"]
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


def _geometry_space(geometry, spec):
    """The geometry space an :class:`OnDemandRays` reads first (see its ``geometry``)."""
    from ._geometry_space import GeometrySpace, read_geometry_space, same_rays

    if geometry is None:
        return None
    if isinstance(geometry, GeometrySpace):
        space = geometry
    elif isinstance(geometry, str) and geometry == "auto":
        from ._geometry_files import default_geometry_file

        path = default_geometry_file()
        if path is None:
            return None
        space = read_geometry_space(path)
        return space if same_rays(space.spec, spec) else None
    else:
        space = read_geometry_space(geometry)
    if not same_rays(space.spec, spec):
        raise ValueError("the geometry space was solved with other rays than the "
                         "specification it is asked to extend")
    return space


def _merge_bundles(parts, path):
    """Merge bundle files into ``path`` (their rays and solver records); remove the parts."""
    import pandas as pd

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
