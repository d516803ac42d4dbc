"""Two causes at once: the rays of a pair of causes, stored, read back and interpolated.

A real skin stiffens *and* is pre-stressed, or stiffens over a hypodermis thicker
than assumed.  The log deflections of two causes do not add (measured: off by up
to 200 % of M for stiffening with pre-tension), so a pair needs rays of its own:
the rays over ``(r, c1, c2)``, where ``c1`` runs over every node of the first
cause and ``c2`` over a subset of the second's nodes (:class:`CausePair`).

Only the rays with *both* causes away from neutral are new FE runs
(:func:`pair_rays`, :func:`pair_bundles`); the edges are the single causes'
spaces, so the pair's slice at ``c2 = neutral`` *is* the first cause's space and
its slice at ``c1 = neutral`` the second's (:func:`assemble_pair_space`).  A pair
space is stored beside the single ones, in the ``pairs/`` folder of the
scale-free space, as one Parquet file per pair.

Off its nodes a pair is read by :class:`skinsuction.space.PairRayInterpolant`
(:mod:`._pair_interpolate`).

Examples
--------
>>> from skinsuction.space import default_registry
>>> reg = default_registry()
>>> pair = pair_from_config({"causes": ["strain_stiffening", "pre_tension"],
...                          "nodes": [1.0, 1.05, 1.1, 1.2]}, reg)
>>> pair.name, pair.symbols
('strain_stiffening_and_pre_tension', ('X2d', 'lambda0'))
>>> spec = RaySpec([2, 6], [0.01, 0.1, 1.0], load_max=100.0)
>>> len(pair_rays(spec, pair))  # (8 - 1) x (4 - 1) new rays per probe and X1h/X1d
126
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pandas as pd

from ._causes import Cause
from ._ray_space import RaySpace, fill_rays
from ._rays import RaySpec, _ray_params, bundle_id, ray_id
from ._storage import _read_parquet, _write_parquet, round_sig

log = logging.getLogger(__name__)

__all__ = ["CausePair", "pair_from_config", "pairs_from_config", "pair_rays", "pair_bundles",
           "PairRaySpace", "assemble_pair_space", "read_pair_space", "read_pair_spaces",
           "space_causes", "PAIRS_FOLDER"]

#: The folder of a scale-free space that holds its pair spaces.
PAIRS_FOLDER = "pairs"


@dataclass(frozen=True)
class CausePair:
    """Two causes in one model: every node of ``first`` times ``second``'s nodes.

    Attributes
    ----------
    first : Cause
        The cause whose every node is simulated (the pair at ``second``'s
        neutral value is this cause's space exactly).
    second : Cause
        The other cause, with the pair's nodes (a subset of its own, with its
        neutral value and at least four nodes, for cubic interpolation).
    """

    first: Cause
    second: Cause

    @property
    def name(self) -> str:
        """``<first>_and_<second>``: the file and job name of the pair."""
        return f"{self.first.name}_and_{self.second.name}"

    @property
    def causes(self) -> tuple:
        """``(first, second)``."""
        return (self.first, self.second)

    @property
    def cause_names(self) -> tuple:
        """The two causes' names."""
        return (self.first.name, self.second.name)

    @property
    def symbols(self) -> tuple:
        """The two parameters' symbols."""
        return (self.first.symbol, self.second.symbol)

    def to_dict(self) -> dict:
        """Plain JSON-able values (:meth:`from_dict` reads them back)."""
        return {"first": self.first.to_dict(), "second": self.second.to_dict()}

    @classmethod
    def from_dict(cls, d: dict) -> "CausePair":
        """A pair of :meth:`to_dict`'s form."""
        return cls(Cause.from_dict(d["first"]), Cause.from_dict(d["second"]))


def pair_from_config(entry: dict, registry: dict, where: str = "scale_free_space.pairs") -> CausePair:
    """One pair of the configuration: ``{causes: [first, second], nodes: [...]}``.

    ``nodes`` are the second cause's nodes in the pair: a subset of its own that
    holds its neutral value, at least four (cubic interpolation).

    Parameters
    ----------
    entry : dict
    registry : dict
        ``{name: Cause}`` (:func:`registry_from_config`).
    where : str
        The configuration key, for error messages.

    Returns
    -------
    CausePair

    Raises
    ------
    ValueError
        Naming ``where`` and what is wrong.
    """
    try:
        first, second = (str(n) for n in entry["causes"])
    except (KeyError, TypeError, ValueError):
        raise ValueError(f"{where}: 'causes' must name two causes, got {entry!r}") from None
    for n in (first, second):
        if n not in registry:
            raise ValueError(f"{where}: no cause {n!r} in scale_free_space.causes "
                             f"({', '.join(sorted(registry))})")
    if first == second:
        raise ValueError(f"{where}: the two causes must differ, got {first!r} twice")
    a, b = registry[first], registry[second]
    if a.keyword == b.keyword:
        raise ValueError(f"{where}: {first!r} and {second!r} set the same model keyword "
                         f"{a.keyword!r}")
    nodes = [float(v) for v in entry.get("nodes", b.nodes)]
    unknown = [v for v in nodes if not any(math.isclose(v, w, abs_tol=1e-12) for w in b.nodes)]
    if unknown:
        raise ValueError(f"{where}.nodes: {unknown} are not nodes of {second!r} "
                         f"({list(b.nodes)}): the pair's edge is that cause's space")
    if len(nodes) < 4:
        raise ValueError(f"{where}.nodes: at least 4 nodes of {second!r} are needed (cubic "
                         f"interpolation), got {nodes}")
    try:
        b = replace(b, nodes=tuple(sorted(nodes)))
    except ValueError as err:
        raise ValueError(f"{where}.nodes: {err}") from None
    return CausePair(a, b)


def pairs_from_config(entries, registry: dict) -> dict:
    """``{name: CausePair}`` of the ``scale_free_space.pairs`` list (empty if none)."""
    out = {}
    for i, entry in enumerate(entries or []):
        pair = pair_from_config(entry, registry, f"scale_free_space.pairs[{i}]")
        if pair.name in out:
            raise ValueError(f"scale_free_space.pairs[{i}]: {pair.name} is listed twice")
        out[pair.name] = pair
    return out


# ------------------------------------------------------------------------- the rays
def _pair_params(spec: RaySpec, probe, ratio, pair: CausePair, c1, c2) -> dict:
    params = _ray_params(spec, probe, ratio, pair.first, c1)
    params.update({k: round_sig(v) for k, v in
                   pair.second.simulate_keywords(c2, spec.x1d_ref).items()})
    return params


def pair_rays(spec: RaySpec, pair: CausePair) -> list[dict]:
    """The new FE rays of a pair: both causes away from neutral.

    Returns
    -------
    list of dict
        ``{"ray_id", "probe_mm", "ratio", "coordinate", "coordinate2", "params"}``
        by probe, X1h/X1d, first and second coordinate.
    """
    a, b = pair.causes
    out = []
    for probe in spec.probes_mm:
        for ratio in spec.ratio_nodes:
            for c1 in a.nodes:
                for c2 in b.nodes:
                    if c1 == a.neutral or c2 == b.neutral:
                        continue
                    params = _pair_params(spec, probe, ratio, pair, c1, c2)
                    out.append({"ray_id": ray_id(params), "probe_mm": probe, "ratio": ratio,
                                "coordinate": c1, "coordinate2": c2, "params": params})
    return out


def pair_bundles(spec: RaySpec, pairs: dict, rays_per_job: int = 1) -> dict:
    """``{bundle_id: [ray_id, ...]}``: the FE jobs of the pairs' new rays.

    As :func:`skinsuction.space.ray_bundles`: runs of consecutive X1h/X1d of about
    ``rays_per_job`` rays per (pair, probe).
    """
    out = {}
    n_ratios = len(spec.ratio_nodes)
    for name, pair in pairs.items():
        per_ratio = (len(pair.first.nodes) - 1) * (len(pair.second.nodes) - 1)
        chunks = max(1, min(n_ratios, math.ceil(n_ratios * per_ratio / max(1, int(rays_per_job)))))
        edges = np.linspace(0, n_ratios, chunks + 1).round().astype(int)
        runs = {spec.ratio_nodes[i]: (spec.ratio_nodes[a], spec.ratio_nodes[b - 1])
                for a, b in zip(edges[:-1], edges[1:]) for i in range(a, b)}
        for ray in pair_rays(spec, pair):
            first, last = runs[ray["ratio"]]
            out.setdefault(bundle_id(name, ray["probe_mm"], first, last), []).append(ray["ray_id"])
    return out


# ------------------------------------------------------------------- the space
@dataclass(eq=False)
class PairRaySpace(RaySpace):
    """The rays of a pair of causes: ``cause`` is the first, ``second`` the other.

    ``deflection_mm[probe]`` has shape ``(n_r, n1 * n2, n_p)``, the coordinates
    in row-major order (the first cause's node, then the second's);
    ``coordinates`` is ``(n1 * n2, 2)``.
    """

    second: Cause | None = None

    @property
    def name(self) -> str:
        return f"{self.cause.name}_and_{self.second.name}"

    @property
    def pair(self) -> CausePair:
        """The pair of causes."""
        return CausePair(self.cause, self.second)

    def slice_second(self, j: int) -> RaySpace:
        """The first cause's space at the second cause's ``j``-th node."""
        n2 = len(self.second.nodes)
        return RaySpace(self.cause, self.spec, np.asarray(self.cause.nodes, dtype=float),
                        {p: a[:, j::n2] for p, a in self.deflection_mm.items()},
                        dict(self.metadata))

    def null_slice(self) -> RaySpace:
        """The neo-Hookean rays (both causes neutral)."""
        j = self.second.nodes.index(self.second.neutral)
        return self.slice_second(j).null_slice()

    def frame(self) -> pd.DataFrame:
        rows = []
        p = np.asarray(self.spec.pressures_mbar)
        for probe, a in self.deflection_mm.items():
            for i, r in enumerate(self.spec.ratio_nodes):
                for j, (c1, c2) in enumerate(self.coordinates):
                    rows.append(pd.DataFrame({
                        "probe_mm": probe, "ratio": r, "coordinate": c1, "coordinate2": c2,
                        "pressure_mbar": p, "deflection_mm": a[i, j]}))
        return pd.concat(rows, ignore_index=True)


def _pair_coordinates(pair: CausePair) -> np.ndarray:
    return np.array([(c1, c2) for c1 in pair.first.nodes for c2 in pair.second.nodes])


def assemble_pair_space(bundle_paths, singles: dict, out_path, spec: RaySpec, pair: CausePair,
                        config: dict | None = None) -> PairRaySpace:
    """Assemble a pair's space file (atomic Parquet) from its bundles and the single spaces.

    Parameters
    ----------
    bundle_paths : iterable of path-like
        The pair's bundle files (:func:`pair_bundles`).
    singles : dict
        ``{name: RaySpace}`` with both causes' spaces (their rays are the pair's
        edges; their specification must be ``spec``).
    out_path : path-like
        Conventionally ``<space dir>/pairs/<pair>.parquet``.
    spec : RaySpec
    pair : CausePair
    config : dict, optional
        Recorded in the provenance.

    Returns
    -------
    PairRaySpace

    Raises
    ------
    ValueError
        A single space missing or of another specification, or a ray missing.
    """
    from skinsuction.provenance import collect

    from ._ray_space import coverage_frontier

    for c in pair.causes:
        s = singles.get(c.name)
        if s is None:
            raise ValueError(f"{pair.name}: the {c.name} space is needed for the pair's edge")
        if s.spec.to_dict() != spec.to_dict():
            raise ValueError(f"{pair.name}: the {c.name} space was built with another ray "
                             "specification (rebuild it or the pair)")
    a, b = pair.causes
    n1, n2 = len(a.nodes), len(b.nodes)
    p = np.asarray(spec.pressures_mbar)
    arrays = {}
    for probe in spec.probes_mm:
        arr = np.full((len(spec.ratio_nodes), n1 * n2, p.size), np.nan)
        first = singles[a.name].rays(probe)
        second = singles[b.name].rays(probe)
        own_b = list(singles[b.name].cause.nodes)
        for i1, c1 in enumerate(a.nodes):
            for i2, c2 in enumerate(b.nodes):
                j = i1 * n2 + i2
                if c2 == b.neutral:
                    arr[:, j] = first[:, i1]
                elif c1 == a.neutral:
                    arr[:, j] = second[:, own_b.index(c2)]
        arrays[probe] = arr
    rays = pair_rays(spec, pair)
    ray_info = fill_rays(bundle_paths, rays, arrays, spec, pair.name,
                         lambda ray: (a.nodes.index(ray["coordinate"]) * n2
                                      + b.nodes.index(ray["coordinate2"])))
    n_failed = sum(1 for r in ray_info.values() if not r.get("converged", False))
    space = PairRaySpace(a, spec, _pair_coordinates(pair), arrays, {}, second=b)
    frontier = coverage_frontier(space.slice_second(n2 - 1))
    meta = collect(config=config, space=pair.name, pair=pair.to_dict(),
                   ray_spec=spec.to_dict(), n_rays=len(rays), n_stopped=n_failed, rays=ray_info,
                   coverage_at_last_node=frontier.drop(columns=["reason"]).to_dict(
                       orient="records"))
    space = PairRaySpace(a, spec, _pair_coordinates(pair), arrays, meta, second=b)
    Path(out_path).parent.mkdir(parents=True, exist_ok=True)
    _write_parquet(space.frame(), out_path, meta)
    log.info("%s space: %d new rays (%d stopped early) -> %s", pair.name, len(rays), n_failed,
             out_path)
    return space


def read_pair_space(path) -> PairRaySpace:
    """Read a pair's space written by :func:`assemble_pair_space`.

    Raises
    ------
    ValueError
        If the file is not a pair space.
    """
    frame, meta = _read_parquet(path)
    if "pair" not in meta or "ray_spec" not in meta:
        raise ValueError(f"{path}: not the space of a pair of causes (rebuild it with the "
                         "workflow)")
    spec = RaySpec(**meta["ray_spec"])
    pair = CausePair.from_dict(meta["pair"])
    a, b = pair.causes
    n2 = len(b.nodes)
    p = np.asarray(spec.pressures_mbar)
    arrays = {}
    for probe, g in frame.groupby("probe_mm"):
        arr = np.full((len(spec.ratio_nodes), len(a.nodes) * n2, p.size), np.nan)
        i = np.searchsorted(np.asarray(spec.ratio_nodes), g["ratio"].to_numpy(float))
        j = (np.searchsorted(np.asarray(a.nodes), g["coordinate"].to_numpy(float)) * n2
             + np.searchsorted(np.asarray(b.nodes), g["coordinate2"].to_numpy(float)))
        k = np.searchsorted(p, g["pressure_mbar"].to_numpy(float))
        arr[i, j, k] = g["deflection_mm"].to_numpy(float)
        arrays[float(probe)] = arr
    return PairRaySpace(a, spec, _pair_coordinates(pair), arrays, meta, second=b)


def read_pair_spaces(space_dir) -> dict:
    """``{name: PairRaySpace}`` of a scale-free space's ``pairs/`` folder (empty if none).

    Raises
    ------
    ValueError
        Naming a file of the folder that is not a pair space.
    """
    d = Path(space_dir)
    if d.is_file():
        d = d.parent
    out = {}
    for path in sorted((d / PAIRS_FOLDER).glob("*.parquet")):
        try:
            s = read_pair_space(path)
        except Exception as err:  # pyarrow raises many types for a bad file
            raise ValueError(f"{path}: not a pair space ({type(err).__name__}: "
                             f"{' '.join(str(err).split())[:200]})") from None
        if s.name in out:  # a shipped pair is one file per probe: put them together
            first = out[s.name]
            first.deflection_mm.update(s.deflection_mm)
            first.metadata["rays"] = {**first.metadata.get("rays", {}),
                                      **s.metadata.get("rays", {})}
        else:
            out[s.name] = s
    return out


def space_causes(space: RaySpace) -> tuple:
    """The causes a space frees, in theta's order: ``()``, ``(cause,)`` or a pair's two."""
    if space.cause is None:
        return ()
    second = getattr(space, "second", None)
    return (space.cause,) if second is None else (space.cause, second)
