"""The neo-Hookean space over the subject's geometry: rays at any layers by interpolation.

A measurement with its own layers (ultrasound, OCT) needs the neo-Hookean rays
of its probe at its own ``t_d / a`` and ``t_h / a``.  Solving them costs 16 FE
rays a probe (10-40 s of CPU); this space holds them on a grid of the
dimensionless geometry instead, solved once at ``a = 1 mm`` (geometric
similarity, M(s a, s t_d, s t_h) = s M), and a new subject's rays are
interpolated from it: a lookup.

On each ray of the specification (an X1h/X1d node, a load node) the log of the
deflection is interpolated by local cubic Lagrange polynomials in
``log(t_d / a)`` and ``log(t_h / a)`` (:class:`LagrangeAxis`, a 4 x 4 stencil).
The nodes of ``t_d / a`` are denser below 0.65, where the dermis turns from a
membrane into a plate under a soft hypodermis (docs/geometry.md).  A ray that
stopped before the last load at a stencil node makes the interpolated ray stop
there too: the space never reports a load it has not simulated around.

The FE model stays the reference: a geometry outside the grid, or a ray
specification the grid was not built with, is solved on demand
(:class:`skinsuction.space.OnDemandRays`), which also reads this space first.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np
import pandas as pd

from ._lagrange import LagrangeAxis
from ._rays import RaySpec, _ray_params, ray_id
from ._storage import _read_parquet, round_sig

__all__ = ["GeometryGrid", "GeometrySpace", "assemble_geometry_space",
           "read_geometry_space", "GEOMETRY_FOLDER", "same_rays",
           "cause_coordinates", "cause_geometry_space"]

#: The folder of a scale-free space that holds its geometry space.
GEOMETRY_FOLDER = "geometry"

#: The file of the neo-Hookean geometry space in that folder.
GEOMETRY_FILE = "neo_hookean.parquet"

#: Digits of a geometry node (its ray id and cache name).
_NODE_DIGITS = 4


def _nodes(values, name: str) -> tuple:
    out = tuple(round_sig(float(v), _NODE_DIGITS) for v in values)
    if len(out) < 5 or not all(b > a > 0 for a, b in zip(out, out[1:])):
        raise ValueError(f"{name}: at least 5 positive, strictly increasing nodes (a cubic "
                         f"stencil and a shifted one for the error estimate), not {values!r}")
    return out


@dataclass(frozen=True)
class GeometryGrid:
    """The nodes of the dimensionless geometry: ``t_d / a`` and ``t_h / a``.

    Parameters
    ----------
    td_nodes, th_nodes : sequence of float
        Strictly increasing, at least 5 each (a cubic stencil, and a shifted one
        for the error estimate), rounded to 4 significant digits.

    Examples
    --------
    >>> g = GeometryGrid([0.2, 0.4, 0.8, 1.6, 3.2], [0.5, 1, 2, 4, 8])
    >>> g.covers(0.3, 3.0), g.covers(0.1, 3.0)
    (True, False)
    >>> len(g.points)
    25
    """

    td_nodes: tuple
    th_nodes: tuple

    def __post_init__(self):
        object.__setattr__(self, "td_nodes", _nodes(self.td_nodes, "t_d_over_a"))
        object.__setattr__(self, "th_nodes", _nodes(self.th_nodes, "t_h_over_a"))

    @classmethod
    def from_config(cls, section: dict) -> "GeometryGrid":
        """From ``scale_free_space.geometry``: ``{t_d_over_a: [...], t_h_over_a: [...]}``."""
        missing = [k for k in ("t_d_over_a", "t_h_over_a") if k not in section]
        if missing:
            raise ValueError(f"scale_free_space.geometry needs {missing}")
        return cls(section["t_d_over_a"], section["t_h_over_a"])

    def to_dict(self) -> dict:
        return {"t_d_over_a": list(self.td_nodes), "t_h_over_a": list(self.th_nodes)}

    @property
    def points(self) -> list:
        """Every node ``(t_d / a, t_h / a)``, by ``t_d`` then ``t_h``."""
        return [(d, h) for d in self.td_nodes for h in self.th_nodes]

    def covers(self, td_a: float, th_a: float) -> bool:
        """Whether the geometry lies inside the grid (edges included)."""
        return (self.td_nodes[0] <= td_a <= self.td_nodes[-1]
                and self.th_nodes[0] <= th_a <= self.th_nodes[-1])

    def ray_ids(self, spec: RaySpec, td_a: float | None = None, cause=None,
                th_nodes=None) -> list:
        """The FE rays of the grid (at ``a = 1 mm``), or of one ``t_d / a`` node.

        They are the ray ids :class:`OnDemandRays` solves at those layers, so the
        grid's rays and the rays on demand are the same FE runs.  With a ``cause``
        (not a thickness), its rays at each of its nodes but the neutral one,
        ordered by ``t_d``, ``t_h``, cause node, X1h/X1d.  ``th_nodes``: only these
        ``t_h / a`` nodes (a job's share).
        """
        tds = self.td_nodes if td_a is None else (round_sig(td_a, _NODE_DIGITS),)
        ths = self.th_nodes if th_nodes is None else tuple(round_sig(h, _NODE_DIGITS)
                                                           for h in th_nodes)
        coords = [None] if cause is None else cause_coordinates(cause)
        return [ray_id(_ray_params(spec, 2.0, r, cause, c, {"t_d": d, "t_h": h}, digits=6))
                for d in tds for h in ths for c in coords for r in spec.ratio_nodes]


def cause_coordinates(cause) -> list:
    """A cause's nodes but the neutral one: the rays its geometry space holds (the
    neutral node is the neo-Hookean ray)."""
    if cause.geometric:
        raise ValueError(f"{cause.name}: a thickness cause's rays are neo-Hookean rays at "
                         "other layers, read off the neo-Hookean geometry space")
    return [float(c) for c in cause.nodes if c != cause.neutral]


class GeometrySpace:
    """A model's rays over the dimensionless geometry, read by interpolation.

    Parameters
    ----------
    spec : RaySpec
        The ray specification the grid was solved with (ratio nodes, loads,
        mesh): rays are served only to an :class:`OnDemandRays` of the same one.
    grid : GeometryGrid
    deflection : ndarray, shape (n_td, n_th, n_r, n_p) or (n_td, n_th, n_c, n_r, n_p)
        M / a at each node, (cause node,) X1h/X1d node and pressure of ``spec``
        (NaN beyond where a ray stopped); stored in single precision (6e-8 of M).
    provenance : dict, optional
    cause : str, optional
        The cause whose rays these are (None: the neo-Hookean model); then
        ``deflection`` has an axis of its ``coordinates``.
    coordinates : sequence of float, optional
        The cause's nodes held (all but the neutral one, :func:`cause_coordinates`).
    """

    def __init__(self, spec: RaySpec, grid: GeometryGrid, deflection, provenance=None,
                 cause: str | None = None, coordinates=None):
        m = np.asarray(deflection, dtype=float)
        self.cause = cause
        self.coordinates = (tuple(float(c) for c in coordinates) if cause is not None
                            else (math.nan,))
        shape = (len(grid.td_nodes), len(grid.th_nodes), len(self.coordinates),
                 len(spec.ratio_nodes), len(spec.pressures_mbar))
        if cause is None:
            shape = shape[:2] + shape[3:]
        if m.shape != shape:
            raise ValueError(f"deflections of shape {m.shape}, the grid needs {shape}")
        self.spec, self.grid, self.provenance = spec, grid, dict(provenance or {})
        self.deflection = m
        self.path = None  # the file read, if any: a cause's space lies beside it
        m5 = m if cause is not None else m[:, :, None]
        with np.errstate(divide="ignore", invalid="ignore"):
            self._log = np.log(np.where(m5 > 0, m5, np.nan))
        self._zero = np.all(m5 == 0, axis=(0, 1, 2, 3))  # the load 0
        self._td = LagrangeAxis(np.log(grid.td_nodes))
        self._th = LagrangeAxis(np.log(grid.th_nodes))

    def covers(self, probe_mm: float, t_d: float, t_h: float) -> bool:
        """Whether the probe and layers (mm) lie inside the grid."""
        a = probe_mm / 2
        return self.grid.covers(t_d / a, t_h / a)

    def rays(self, probe_mm: float, t_d: float, t_h: float, ratio_nodes=None,
             coordinate: float | None = None, deflection_cap: float | None = None):
        """The rays of one probe at the layers ``t_d``, ``t_h`` (mm).

        Parameters
        ----------
        probe_mm : float
            Aperture diameter ``2 a`` (mm).
        t_d, t_h : float
            Dermis and hypodermis thickness (mm).
        ratio_nodes : sequence of float, optional
            Only these X1h/X1d nodes of the specification (default all).
        coordinate : float, optional
            The cause's node (a cause's space only: one of :attr:`coordinates`).
        deflection_cap : float, optional
            The error estimate weighs only the loads where the ray's deflection is at
            most this (mm, at this probe): a measurement's fit never reads a ray far
            above the measured curve (default: every load).

        Returns
        -------
        rays : ndarray, shape (n_r, 1, n_p)
            Deflections (mm) at the specification's pressures.
        info : dict
            ``source`` ("geometry space"), ``rays``, ``stopped_early``, and
            ``error_estimate`` (n_r,): per ray, the largest change of log M when a
            stencil is shifted by one node, a measure of the interpolation error
            (:class:`OnDemandRays` solves the rays where it exceeds its tolerance).

        Raises
        ------
        ValueError
            Outside the grid, for ratio nodes the specification does not have, or
            for a cause node the space does not hold.
        """
        k = self._coordinate_index(coordinate)
        a = probe_mm / 2
        td_a, th_a = t_d / a, t_h / a
        if not self.grid.covers(td_a, th_a):
            raise ValueError(f"t_d/a = {td_a:g}, t_h/a = {th_a:g} is outside the geometry "
                             f"space (t_d/a {self.grid.td_nodes[0]:g}-{self.grid.td_nodes[-1]:g},"
                             f" t_h/a {self.grid.th_nodes[0]:g}-{self.grid.th_nodes[-1]:g})")
        index = _ratio_index(self.spec, ratio_nodes)
        x, y = math.log(td_a), math.log(th_a)
        (i,), (wi,) = self._td.weights([x])
        (j,), (wj,) = self._th.weights([y])
        log_m = self._combine(i, wi, j, wj, k, index)
        m = np.exp(log_m) * a
        m[:, self._zero] = 0.0
        # a ray is cut at its first NaN: beyond, the stencil lacks a node
        cut = np.cumsum(np.isnan(m), axis=1) > 0
        m[cut] = np.nan
        weighed = None if deflection_cap is None else ~(m > deflection_cap)
        info = {"source": "geometry space", "rays": len(index),
                "stopped_early": int(cut[:, -1].sum()),
                "error_estimate": self._error_estimate(log_m, x, y, i, wi, j, wj, k, index,
                                                       weighed)}
        return m[:, None, :], info

    def _coordinate_index(self, coordinate) -> int:
        if self.cause is None:
            if coordinate is not None:
                raise ValueError("the neo-Hookean geometry space has no cause nodes")
            return 0
        hit = [n for n, c in enumerate(self.coordinates)
               if coordinate is not None and math.isclose(c, coordinate, rel_tol=1e-9)]
        if not hit:
            raise ValueError(f"{self.cause}: no node {coordinate!r} in its geometry space "
                             f"(it holds {list(self.coordinates)})")
        return hit[0]

    def _combine(self, i, wi, j, wj, k, index):
        """log M of the rays ``index`` of cause node ``k`` on the 4 x 4 stencil at (i, j)."""
        block = self._log[i:i + wi.size, j:j + wj.size, k][:, :, index]  # (4, 4, n_r, n_p)
        return np.einsum("a,b,abrp->rp", wi, wj, block)

    def _error_estimate(self, log_m, x, y, i, wi, j, wj, k, index, weighed=None):
        """Per ray, the largest change of log M (about the relative error) when either
        axis's stencil is shifted by one node, over the loads where both exist (and
        ``weighed``, a mask of the loads, holds).

        The shifted stencils hold the same cell, so their spread is of the order of
        the interpolation error; a shift that meets a stopped ray is left out.
        """
        spread = np.zeros(len(index))
        for axis, start, n in ((self._td, i, len(self.grid.td_nodes)),
                               (self._th, j, len(self.grid.th_nodes))):
            for s in (start - 1, start + 1):
                if not 0 <= s <= n - 4:
                    continue
                if axis is self._td:
                    other = self._combine(s, axis.weights_at([x], np.array([s]))[0], j, wj, k,
                                          index)
                else:
                    other = self._combine(i, wi, s, axis.weights_at([y], np.array([s]))[0], k,
                                          index)
                d = np.abs(other - log_m)
                d[~np.isfinite(d)] = 0.0
                if weighed is not None:
                    d[~weighed] = 0.0
                spread = np.maximum(spread, d.max(axis=1))
        return spread


def _ratio_index(spec: RaySpec, ratio_nodes) -> list:
    if ratio_nodes is None:
        return list(range(len(spec.ratio_nodes)))
    where = {r: k for k, r in enumerate(spec.ratio_nodes)}
    missing = [r for r in ratio_nodes if r not in where]
    if missing:
        raise ValueError(f"ratio nodes {missing} are not nodes of the ray specification")
    return [where[r] for r in ratio_nodes]


def assemble_geometry_space(bundle_paths, out_path, spec: RaySpec, grid: GeometryGrid,
                            provenance: dict | None = None, cause=None) -> GeometrySpace:
    """Gather the grid's FE rays from bundle files into one geometry space file.

    Parameters
    ----------
    bundle_paths : sequence of path-like
        Files of solved rays (:func:`skinsuction.space.compute_bundle`, or the
        cache files of :class:`OnDemandRays`), holding every ray of
        :meth:`GeometryGrid.ray_ids`.
    out_path : path-like
        Written atomically.
    spec : RaySpec
    grid : GeometryGrid
    provenance : dict, optional
    cause : Cause, optional
        A cause's rays (at its nodes but the neutral one) instead of the
        neo-Hookean ones.

    Returns
    -------
    GeometrySpace

    Raises
    ------
    ValueError
        Naming the rays missing or incomplete (a missing ray is never filled in),
        or the bundle files solved by different FE code or meshes (a build
        resumed or spread over machines must not mix them).
    """
    frames, infos, solved_by = [], {}, {}
    for p in bundle_paths:
        f, meta = _read_parquet(p)
        frames.append(f[["ray_id", "pressure_mbar", "deflection_mm"]])
        infos.update(meta.get("rays") or {})
        solved_by.setdefault(_solver_key(meta), []).append(str(p))
    if len(solved_by) > 1:
        groups = "; ".join(f"{len(v)} file(s) such as {v[0]} with {k}" for k, v in solved_by.items())
        raise ValueError(f"the bundle files were solved by different FE code or meshes: {groups}."
                         " Rebuild the odd ones (delete them and rerun the workflow)")
    rows = pd.concat(frames, ignore_index=True).drop_duplicates(["ray_id", "pressure_mbar"])
    by_ray = {rid: g for rid, g in rows.groupby("ray_id", sort=False)}
    n_p = len(spec.pressures_mbar)
    ids = grid.ray_ids(spec, cause=cause)
    missing = [rid for rid in ids if rid not in by_ray or len(by_ray[rid]) != n_p]
    if missing:
        raise ValueError(f"{len(missing)} of the geometry space's {len(ids)} rays are missing "
                         f"or incomplete, e.g. {missing[:3]}")
    m = np.stack([by_ray[rid].sort_values("pressure_mbar")["deflection_mm"].to_numpy(float)
                  for rid in ids])
    coords = None if cause is None else cause_coordinates(cause)
    shape = (len(grid.td_nodes), len(grid.th_nodes)) + (() if cause is None else (
        len(coords),)) + (len(spec.ratio_nodes), n_p)
    m = m.reshape(shape)
    info = [infos.get(rid, {}) for rid in ids]
    meta = {"spec": spec.to_dict(), "grid": grid.to_dict(),
            "layout": "deflection_mm in C order over (t_d/a, t_h/a, "
                      + ("" if cause is None else f"{cause.symbol}, ") + "X1h/X1d, pressure)",
            "cause": None if cause is None else {"name": cause.name, "keyword": cause.keyword,
                                                 "coordinates": coords},
            "rays": len(ids),
            # the solver's record, compact: only the rays that stopped or needed a fallback
            "stopped_early": {rid: i.get("last_converged_mbar") for rid, i in zip(ids, info)
                              if not i.get("converged", True)},
            "mesh_fallback": {rid: i.get("mesh_fallback") for rid, i in zip(ids, info)
                              if i.get("mesh_fallback")},
            "cpu_s": round(sum(float(i.get("seconds") or 0.0) for i in info), 1),
            "solved_by": json.loads(next(iter(solved_by))) if solved_by else None,
            "provenance": dict(provenance or {})}
    m = m.astype(np.float32).astype(float)  # as stored: 1e-7 of M, far below its errors
    _write_compact(m.reshape(-1), out_path, meta)
    return GeometrySpace(spec, grid, m, meta["provenance"], *_cause_of(meta))


def _solver_key(meta: dict) -> str:
    """What a bundle file's rays depend on besides their ids: the FE code's hash, the mesh
    and its fallbacks, as a JSON key (an on-demand cache file records no hash: None)."""
    keys = ("source_hash", "mesh", "mesh_fallback", "fallback_below_mbar")
    return json.dumps({k: meta.get(k) for k in keys}, sort_keys=True, default=str)


def _cause_of(meta: dict) -> tuple:
    """``(cause name, coordinates)`` of a geometry space file's metadata; Nones if neo-Hookean."""
    cause = meta.get("cause")
    return (None, None) if not cause else (cause["name"], cause["coordinates"])


def _write_compact(values, path, meta: dict) -> None:
    """One float32 column (6e-8 of M), zstd with byte-stream split: a sixth of the
    default size, so the shipped file stays small (the nodes are in ``meta``)."""
    import json

    import pyarrow as pa
    import pyarrow.parquet as pq

    from skinsuction._files import atomic_output
    from skinsuction.provenance import jsonable

    from ._storage import METADATA_KEY

    table = pa.table({"deflection_mm": np.asarray(values, dtype=np.float32)})
    table = table.replace_schema_metadata(
        {METADATA_KEY: json.dumps(jsonable(meta), sort_keys=True).encode()})
    with atomic_output(path) as tmp:
        pq.write_table(table, tmp, compression="zstd", compression_level=9,
                       use_dictionary=False, use_byte_stream_split=True)


def read_geometry_space(path) -> GeometrySpace:
    """Read a geometry space file (:func:`assemble_geometry_space`).

    Raises
    ------
    FileNotFoundError, ValueError
        Naming the file.
    """
    path = Path(path)
    stat = path.stat()
    return _read_cached(str(path.resolve()), stat.st_mtime_ns, stat.st_size)


@lru_cache(maxsize=4)
def _read_cached(path: str, mtime_ns: int, size: int) -> GeometrySpace:
    frame, meta = _read_parquet(path)
    try:
        spec = RaySpec(**meta["spec"])
        grid = GeometryGrid.from_config(meta["grid"])
        cause, coords = _cause_of(meta)
        n = (len(grid.td_nodes), len(grid.th_nodes)) + (() if cause is None else (
            len(coords),)) + (len(spec.ratio_nodes), len(spec.pressures_mbar))
        m = frame["deflection_mm"].to_numpy(float).reshape(n)
        space = GeometrySpace(spec, grid, m, meta.get("provenance"), cause, coords)
    except (KeyError, ValueError, TypeError) as err:
        raise ValueError(f"{path}: not a geometry space file ({err})") from err
    space.path = Path(path)
    return space


def cause_geometry_space(beside: GeometrySpace | None, cause, spec: RaySpec):
    """A cause's geometry space lying beside the neo-Hookean one (``<cause>.parquet`` in
    its folder), if it was solved with the same rays and the cause's nodes; else None.

    Parameters
    ----------
    beside : GeometrySpace or None
        The neo-Hookean geometry space, as read from its file.
    cause : Cause
    spec : RaySpec
        The specification the rays are asked for.
    """
    if beside is None or beside.path is None or cause.geometric:
        return None
    path = beside.path.parent / f"{cause.name}.parquet"
    if not path.is_file():
        return None
    space = read_geometry_space(path)
    if (space.cause != cause.name or not same_rays(space.spec, spec)
            or not np.allclose(space.coordinates, cause_coordinates(cause), rtol=1e-9)):
        return None
    return space


def same_rays(a: RaySpec, b: RaySpec) -> bool:
    """Whether two specifications run the same FE rays (the probes and the fits'
    X1d window aside): only then does a geometry space serve the other's rays."""
    def key(s):
        d = s.to_dict()
        return {k: v for k, v in d.items() if k not in ("probes_mm", "x1d_range")}
    return key(a) == key(b)
