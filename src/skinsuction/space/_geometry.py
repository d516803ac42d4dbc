"""Every probe and the subject's own layers: the spaces of one measurement.

The scale-free space holds rays of the Cutometer probes (2, 4, 6 and 8 mm) for
the paper's layers (dermis and hypodermis 1 mm each).  A measurement with another
aperture, or with its own layer thicknesses (ultrasound, OCT), gets its
neo-Hookean rays solved on demand at exactly that geometry, with the space's ray
specification (:class:`OnDemandRays`), and cached on disk: 16 FE rays per probe,
about 10-20 s of CPU, once per geometry.  Interpolating a precomputed grid over
the geometry instead was measured and rejected: under a soft hypodermis the
deflection changes fourfold between t_d/a = 0.2 and 0.55, and cubic
interpolation on nodes 1.3 apart in t_d/a still missed direct runs by up to 1.1 %
(median 0.3 %), where the space must stay within 0.2 % (docs/geometry.md).

Geometric similarity, M(s a, s t_d, s t_h) = s M(a, t_d, t_h) (tested to
round-off in tests/test_model.py), makes a cached set of rays serve every
geometrically similar measurement: the cache key is the dimensionless geometry
(t_d/a, t_h/a), the rays are scaled by the aperture.

The causes get their own rays at that geometry too, solved on demand
(:func:`spaces_at`); a diagnosis asks only for the X1h/X1d nodes in a window
around its neo-Hookean fit and widens it where a cause's fit reaches its edge
(``ratio_window``).  Without a solver a cause's effect on log M is carried over
from the probes and layers it was simulated for, an approximation the notes
name.
"""

from __future__ import annotations

import hashlib
import logging
import math
import os
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from skinsuction.measured._geometry import DEFAULT_LAYERS_MM, Geometry

from ._causes import BASELINE

log = logging.getLogger(__name__)

__all__ = ["Geometry", "GeometryOutsideSpace", "OnDemandRays", "spaces_at", "ThicknessNuisance",
           "DEFAULT_LAYERS_MM", "default_cache_dir", "window_nodes"]

#: Thicknesses are rounded to this (mm) before rays are solved for them: a
#: measured thickness is not known better, and rounded geometries share a cache.
THICKNESS_RESOLUTION_MM = 0.01


class GeometryOutsideSpace(ValueError):
    """A probe and layers the spaces do not cover (and no on-demand solver is allowed)."""


def default_cache_dir() -> Path:
    """Where on-demand rays are kept: ``$SKINSUCTION_CACHE`` or ``~/.cache/skinsuction``."""
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


def _round_mm(x: float) -> float:
    return round(round(float(x) / THICKNESS_RESOLUTION_MM) * THICKNESS_RESOLUTION_MM, 6)


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


@dataclass(frozen=True)
class ThicknessNuisance:
    """A given layer thickness with its sd, as a nuisance parameter of every fit.

    A measured thickness is not exact (ultrasound and OCT: about 0.05-0.1 mm), and
    0.1 mm of dermis under the 6 mm probe moves the fitted X1h by tens of percent
    (docs/geometry.md).  The fits therefore search ``delta``, the thickness
    offset in units of its sd, with a standard normal prior, and the model's curve
    moves with it by the quadratic through its curves at ``value - sd``,
    ``value``, ``value + sd`` (solved on demand).  A cause whose rays are solved at
    the given layers has brackets of its own rays (``center``, ``minus``, ``plus``
    of that cause); otherwise the brackets are neo-Hookean, and the cause's curve
    moves as the neo-Hookean one does at the same (X1d, X1h): under pre-tension
    that missed the FE curve 0.083 mm of dermis away by 4 % of M (6 mm probe),
    its own brackets by 0.05 % (0.1 % from -0.7 to +1 sd).

    Attributes
    ----------
    keyword : {"t_d", "t_h"}
    value, sd : float
        The given thickness and its sd (mm).
    center, minus, plus : RaySpace
        The model's rays (neo-Hookean, or a cause's at every node) at ``value``,
        ``value - sd`` and ``value + sd``.
    """

    keyword: str
    value: float
    sd: float
    center: object
    minus: object
    plus: object

    @property
    def symbol(self) -> str:
        return self.keyword

    def thickness(self, delta):
        """Thickness (mm) of an offset in sd units."""
        return self.value + np.asarray(delta, dtype=float) * self.sd


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


def _cause_effect(space, probe_mm: float):
    """log M_c - log M_neutral of a cause's rays at one aperture, (n_r, n_c, n_p - 1).

    Interpolated across the cause's probes (cubic Lagrange in log10 of the
    aperture); exactly 0 at the neutral coordinate; None outside its probes.
    """
    from ._lagrange import LagrangeAxis

    probes = np.asarray(space.probes_mm, dtype=float)
    j0 = int(np.argmin(np.abs(np.asarray(space.coordinates) - space.cause.neutral)))
    effect = []
    with np.errstate(divide="ignore", invalid="ignore"):
        for p in probes:
            g = np.log(space.rays(p)[..., 1:])
            g[~np.isfinite(g)] = np.nan
            effect.append(g - g[:, j0:j0 + 1, :])
    effect = np.stack(effect)
    hit = np.flatnonzero(np.isclose(probes, probe_mm, rtol=0, atol=1e-6))
    if hit.size:
        return effect[hit[0]]
    if probes.size < 2:
        return None
    axis = LagrangeAxis(np.log10(probes))
    start, w = axis.weights([math.log10(probe_mm)])
    if np.isnan(w[0, 0]):
        return None
    block = effect[int(start[0]):int(start[0]) + axis.m]
    block = np.where((w[0] == 0.0)[:, None, None, None], 0.0, block)
    return np.tensordot(w[0], block, axes=(0, 0))


def window_nodes(nodes, window=None) -> tuple:
    """The X1h/X1d nodes within ``window = (lo, hi)``, at least 4 (a cubic stencil).

    >>> window_nodes([1e-4, 1e-3, 1e-2, 0.1, 1.0, 2.0], (0.005, 0.5))
    (0.001, 0.01, 0.1, 1.0)
    >>> window_nodes([1e-4, 1e-3, 1e-2, 0.1, 1.0], None)
    (0.0001, 0.001, 0.01, 0.1, 1.0)
    """
    nodes = tuple(float(r) for r in nodes)
    if window is None:
        return nodes
    lo, hi = sorted(float(w) for w in window)
    inside = [i for i, r in enumerate(nodes) if lo * (1 - 1e-9) <= r <= hi * (1 + 1e-9)]
    i0 = inside[0] if inside else int(np.searchsorted(nodes, lo))
    i1 = inside[-1] + 1 if inside else i0
    while i1 - i0 < min(4, len(nodes)):  # widen, alternately up and down
        if i1 < len(nodes) and (i1 - i0) % 2 == 0 or i0 == 0:
            i1 += 1
        else:
            i0 -= 1
    return nodes[i0:i1]


def spaces_at(spaces: dict, probes, geometry: Geometry, on_demand: OnDemandRays | None = None,
              solve_causes: bool = True, ratio_window=None):
    """The ray spaces of one measurement: every model at its probes and layers.

    Parameters
    ----------
    spaces : dict name -> RaySpace
        As read by :func:`skinsuction.space.read_ray_spaces`.
    probes : iterable of float
        Apertures (mm) of the measurement.
    geometry : Geometry
    on_demand : OnDemandRays, optional
        Solves the rays of a probe or geometry the space lacks; without it such a
        measurement raises :class:`GeometryOutsideSpace`.
    solve_causes : bool
        With ``on_demand``, also solve every cause's rays at this geometry (about
        700 FE rays for two probes, once: cached).  Otherwise a cause's effect on
        log M is carried over from the layers and probes it was simulated for, an
        approximation measured to fail at other dermis thicknesses
        (docs/geometry.md), and the notes say so.
    ratio_window : (lo, hi), optional
        X1h/X1d range of the causes' rays solved on demand: only the nodes within
        it (:func:`window_nodes`), each cause's space is cut to them.  A
        diagnosis centres it on the neo-Hookean fit and widens it where a cause's
        fit reaches its edge; a fraction of the FE rays.  Default: every node.

    Returns
    -------
    (dict name -> RaySpace, list of str)
        The spaces (the neo-Hookean one at the measurement's geometry, each cause
        as its effect on it), and notes for the report: a cause left out (its
        thickness is given, or it is not simulated for these probes), rays solved
        on demand, a cause's effect carried over from the layers or probes it was
        simulated for.

    Examples
    --------
    >>> import numpy as np
    >>> from skinsuction.space import RaySpace, RaySpec
    >>> spec = RaySpec(probes_mm=[2, 6], ratio_nodes=[0.01, 0.1], load_max=100.0,
    ...                load_steps=4)
    >>> rays = {p: np.linspace(0, 1, 5)[None, None, :] * np.ones((2, 1, 1)) for p in (2., 6.)}
    >>> base = RaySpace(None, spec, np.array([np.nan]), rays)
    >>> out, notes = spaces_at({"neo_hookean": base}, [6.0], Geometry())
    >>> out["neo_hookean"].probes_mm, notes
    ((6.0,), [])
    >>> spaces_at({"neo_hookean": base}, [4.0], Geometry())  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    skinsuction.space._geometry.GeometryOutsideSpace: no neo-Hookean rays of the 4 mm probe for ...
    """
    from ._ray_space import RaySpace

    probes = [float(p) for p in probes]
    base = spaces[BASELINE]
    notes = []
    t_d, t_h = geometry.t_d, geometry.t_h
    if not geometry.is_default:
        t_d, t_h = _round_mm(t_d), _round_mm(t_h)
        if abs(t_d - geometry.t_d) > 1e-9 or abs(t_h - geometry.t_h) > 1e-9:
            notes.append(f"thicknesses rounded to {THICKNESS_RESOLUTION_MM:g} mm for the FE "
                         f"rays: t_d = {t_d:g}, t_h = {t_h:g} mm")
    default = geometry.is_default
    rays, solved = {}, []
    own_brackets = set()  # causes solved at these layers: thickness brackets of their own
    for p in probes:
        if default and base.has_probe(p):
            rays[p] = base.rays(p)
            continue
        if on_demand is None:
            raise GeometryOutsideSpace(
                f"no neo-Hookean rays of the {p:g} mm probe for t_d = {t_d:g}, t_h = {t_h:g} mm "
                f"in the space (it has {', '.join(f'{q:g}' for q in base.probes_mm)} mm with "
                "1 mm layers); allow solving them on demand")
        rays[p], info = on_demand.rays(p, t_d, t_h)
        solved.append((p, info))
    for p, info in solved:
        notes.append(f"neo-Hookean rays of the {p:g} mm probe at t_d = {t_d:g}, t_h = {t_h:g} mm"
                     f" solved on demand ({info['rays']} FE rays, {info['stopped_early']} "
                     f"stopped early; cached in {info['cache']})")
    spec = replace(base.spec, probes_mm=tuple(probes))
    meta = {**base.metadata, "geometry": geometry.to_dict()}
    out = {BASELINE: RaySpace(None, spec, np.array([math.nan]), rays, meta)}
    for name, space in spaces.items():
        if name == BASELINE:
            continue
        cause = space.cause
        if cause.geometric and cause.keyword in geometry.given:
            notes.append(f"{name}: not a free cause, the {cause.symbol} is given "
                         f"({getattr(geometry, cause.keyword):g} mm)")
            continue
        if default and all(space.has_probe(p) for p in probes):
            out[name] = RaySpace(cause, spec, space.coordinates,
                                 {p: space.rays(p) for p in probes}, space.metadata)
            continue
        if on_demand is not None and solve_causes:
            nodes = window_nodes(base.spec.ratio_nodes, ratio_window)
            keep = [base.spec.ratio_nodes.index(r) for r in nodes]
            arrays, n_rays, n_stopped = {}, 0, 0
            for p in probes:
                if default and space.has_probe(p):
                    arrays[p] = space.rays(p)[keep]
                    continue
                arrays[p], info = on_demand.rays(p, t_d, t_h, cause, **_subset(nodes, base.spec.ratio_nodes))
                n_rays += info["rays"]
                n_stopped += info["stopped_early"]
            window = ("" if len(nodes) == len(base.spec.ratio_nodes) else
                      f", X1h/X1d {nodes[0]:g}-{nodes[-1]:g} only ({len(nodes)} of "
                      f"{len(base.spec.ratio_nodes)} nodes)")
            notes.append(f"{name}: its rays at this geometry solved on demand ({n_rays} FE "
                         f"rays, {n_stopped} stopped early{window})")
            out[name] = RaySpace(cause, replace(spec, ratio_nodes=nodes),
                                 np.asarray(cause.nodes, dtype=float), arrays,
                                 {**space.metadata, "geometry": geometry.to_dict()})
            own_brackets.add(name)
            continue
        arrays = {}
        for p in probes:
            effect = _cause_effect(space, p)
            if effect is None:
                break
            with np.errstate(divide="ignore", invalid="ignore"):
                g = np.log(np.where(rays[p][..., 1:] > 0, rays[p][..., 1:], np.nan)) + effect
            full = np.zeros(g.shape[:-1] + (g.shape[-1] + 1,))
            full[..., 1:] = np.exp(g)
            arrays[p] = full
        if len(arrays) < len(probes):
            notes.append(f"{name}: simulated for the {', '.join(f'{q:g}' for q in space.probes_mm)}"
                         f" mm probes only, not {', '.join(f'{q:g}' for q in probes)} mm")
            continue
        where = []
        if not default:
            where.append(f"{DEFAULT_LAYERS_MM[0]:g} mm + {DEFAULT_LAYERS_MM[1]:g} mm layers")
        if any(not space.has_probe(p) for p in probes):
            where.append(f"the {', '.join(f'{q:g}' for q in space.probes_mm)} mm probes")
        notes.append(f"{name}: its effect on the deflection was simulated for "
                     f"{' and '.join(where)} and is carried over to this measurement "
                     "(an approximation)")
        out[name] = RaySpace(cause, spec, space.coordinates, arrays,
                             {**space.metadata, "geometry": geometry.to_dict()})
    nuisance = _nuisances(out[BASELINE], probes, geometry, (t_d, t_h), on_demand, notes)
    for name, space in out.items():
        space.nuisance = nuisance
        if nuisance and name in own_brackets:
            space.nuisance = _nuisances(space, probes, geometry, (t_d, t_h), on_demand, [],
                                        base.spec.ratio_nodes)
    if nuisance and own_brackets:
        notes.append(f"{', '.join(sorted(own_brackets))}: the thickness nuisance moves each "
                     "cause's curve by its own rays at ±1 sd (solved on demand)")
    return out, notes


def _subset(nodes, full) -> dict:
    """``{"ratio_nodes": nodes}`` if they are fewer than the ``full`` nodes, else
    nothing: a solver is asked for a cut window only."""
    return {"ratio_nodes": tuple(nodes)} if len(nodes) < len(full) else {}


def _nuisances(center, probes, geometry, layers, on_demand, notes, full_nodes=()) -> tuple:
    """A :class:`ThicknessNuisance` per given thickness with an sd (rays on demand):
    brackets of ``center``'s own model (neo-Hookean, or a cause at every node)."""
    from ._ray_space import RaySpace

    cause = center.cause
    coordinates = np.array([math.nan]) if cause is None else np.asarray(cause.nodes, float)
    out = []
    for i, key in enumerate(("t_d", "t_h")):
        sd = (geometry.sd or {}).get(key)
        if key not in geometry.given or not sd:
            continue
        if on_demand is None:
            notes.append(f"the {key} sd ({sd:g} mm) is not used: its rays would be solved on "
                         "demand, which is not allowed")
            continue
        value = layers[i]
        brackets = []
        for t in (value - sd, value + sd):
            t = max(_round_mm(t), THICKNESS_RESOLUTION_MM)
            other = list(layers)
            other[i] = t
            rays = {p: on_demand.rays(p, *other, cause, **_subset(center.spec.ratio_nodes,
                                                                   full_nodes))[0]
                    for p in probes}
            brackets.append(RaySpace(cause, center.spec, coordinates, rays,
                                     {**center.metadata, key: t}))
        out.append(ThicknessNuisance(key, value, float(sd), center, *brackets))
        notes.append(f"the given {key} = {value:g} ± {sd:g} mm is a nuisance parameter of every "
                     "fit (Gaussian prior; neo-Hookean rays at ±1 sd solved on demand)")
    return tuple(out)
