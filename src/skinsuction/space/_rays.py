"""The scale-free simulated space: FE rays, thanks to the scaling law.

The model obeys ``M(s X1d, s X1h, s X2d, s X2h, s p; t_d, t_h, lambda0) =
M(X1d, X1h, X2d, X2h, p; t_d, t_h, lambda0)`` (tested in tests/test_model.py).
With ``r = X1h / X1d``, the cause's dimensionless coordinate ``c``
(``X2d / X1d``, ``t_d`` or ``lambda0``, see :mod:`._causes`) and the load
``q = p / X1d``,

    M(X1d, r, c, p) = R(r, c, q = p / X1d),

where ``R(r, c, .)`` is *one* FE curve (a ray) run at ``X1d = x1d_ref`` to
``q = load_max`` (:class:`RaySpec`).  So a space over (X1d, X1h, c, p) needs FE
runs on the 2-D grid (r, c) only, and the neo-Hookean space a 1-D set of rays
over r; a curve up to ``p_max`` is covered for ``X1d >= p_max / load_max``.
Where a ray stopped early (large deflections over a very soft hypodermis) it is
NaN beyond, candidates that need that part get cost +inf, and the stop is
recorded (:func:`coverage_frontier`).

Interpolation (:class:`RayInterpolant`):

* across rays, cubic Lagrange in ``log10 r`` and in the cause's axis
  coordinate (:meth:`Cause.to_axis`), applied to ``log M`` (the deflection
  varies by decades over r; its logarithm is close to a smooth sigmoid in
  log r), at the ray loads;
* then along the load of the ray, cubic Lagrange on M at ``q``.

The identification tabulates the neo-Hookean rays of a probe once per curve
(:class:`TabulatedInterpolant`).

Storage: the FE jobs write bundles of rays (one per model, probe and r,
:func:`ray_bundles`); :func:`assemble_ray_space` writes one Parquet file per
model (``results/simulated_space/scale_free/<model>.parquet``) with one row
per (probe, r, c, pressure) and the cause, the axes, the coverage and the
provenance in the schema metadata; ``neo_hookean.parquet`` holds the rays at
the neutral coordinate of every cause (the same FE runs).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from ._causes import BASELINE, Cause
from ._storage import (
    AXES,
    POINT_ID_PATTERN,
    _fmt,
    _read_parquet,
    _write_parquet,
    parse_point_id,
    point_id,
    round_sig,
)

log = logging.getLogger(__name__)

__all__ = [
    "RaySpec",
    "RaySpace",
    "ray_id",
    "parse_ray_id",
    "RAY_ID_PATTERN",
    "rays_of",
    "ray_bundles",
    "bundle_id",
    "BUNDLE_ID_PATTERN",
    "coverage_frontier",
    "assemble_ray_space",
    "read_ray_space",
    "read_ray_spaces",
    "SpaceMissingError",
    "SpaceFileError",
]

#: Extra keywords of the model beyond the grid axes of a point id, with defaults.
EXTRA_KEYWORDS = {"prestretch": 1.0}

#: Snakemake wildcard constraint of a ray id.
RAY_ID_PATTERN = POINT_ID_PATTERN + r"(?:__[a-z][a-z0-9_]*=[^/_]+)*"


class SpaceMissingError(FileNotFoundError):
    """The ray spaces the diagnosis needs are not there (build them with the workflow)."""


class SpaceFileError(ValueError):
    """A file of the space directory is not a ray space of the diagnosis."""


# ------------------------------------------------------------------------ ray ids
def ray_id(params: dict) -> str:
    """Name of one FE ray: the point id plus ``__keyword=value`` for extra keywords.

    Extra keywords (``prestretch``) at their default value are left out, so a
    neo-Hookean ray has the plain point id.

    >>> ray_id(dict(probe_mm=6, bottom="fixed", x1d=0.02, x1h=2e-4, prestretch=1.05))
    'p6_fixed_x1d0.02_x1h0.0002_x2d0_x2h0_td1_th1__prestretch=1.05'
    >>> parse_ray_id(_)["prestretch"]
    1.05
    """
    base = point_id({k: v for k, v in params.items() if k in AXES})
    extras = ""
    for key in sorted(set(params) - set(AXES)):
        if key not in EXTRA_KEYWORDS:
            raise ValueError(f"unknown model keyword {key!r} in a ray")
        value = round_sig(params[key])
        if value != EXTRA_KEYWORDS[key]:
            extras += f"__{key}={_fmt(value)}"
    return base + extras


def parse_ray_id(rid: str) -> dict:
    """The model keywords of a ray id (inverse of :func:`ray_id`), extras included."""
    base, *extras = rid.split("__")
    out = parse_point_id(base)
    out.update(EXTRA_KEYWORDS)
    for item in extras:
        key, sep, text = item.partition("=")
        if not sep or key not in EXTRA_KEYWORDS:
            raise ValueError(f"not a ray id: {rid!r} (bad extra {item!r})")
        out[key] = round_sig(float(text))
    return out


# ---------------------------------------------------------------- ray specification
@dataclass(frozen=True)
class RaySpec:
    """The scale-free simulated space: where and how its rays are run.

    Attributes
    ----------
    probes_mm : tuple of float
    ratio_nodes : tuple of float
        Nodes of r = X1h / X1d (ascending, > 0), interpolated in log10 r.
    load_max : float
        Largest load p / X1d of a ray (mbar/MPa); a measured curve up to
        ``p_max`` reaches X1d down to ``p_max / load_max``.
    load_steps : int
        Load steps of a ray.
    load_refine : int
        Extra load nodes near 0: the first step halved ``load_refine`` times
        (``load_max / load_steps / 2**k``).  A strongly stiffening dermis bends M(p)
        within the first even step (X2d/X1d = 1000: 4.8 % interpolation error with
        none, 0.08 % with 4).  They are solved in the ray's one run (the onset),
        as the main solve's modified Newton converges slowly after tiny steps.
    x1d_range : (float, float)
        Search window of X1d (MPa) of the fits; its lower end is raised to
        ``p_max / load_max`` for a curve up to ``p_max``.
    x1d_ref : float
        X1d at which the rays are run (MPa); any value gives the same space (the
        scaling law), it only sets the pressures of the FE runs.
    bottom : str
    mesh : dict
        Mesh settings passed to the model.
    fallback : tuple of dict
        Fallback meshes for a ray that stops early (see
        :func:`skinsuction.space.solve_with_fallbacks`).
    """

    probes_mm: tuple
    ratio_nodes: tuple
    load_max: float
    load_steps: int = 40
    load_refine: int = 0
    x1d_range: tuple = (0.001, 1.0)
    x1d_ref: float = 0.01
    bottom: str = "fixed"
    mesh: dict = field(default_factory=dict)
    fallback: tuple = ()

    def __post_init__(self):
        set_ = object.__setattr__
        set_(self, "probes_mm", tuple(float(p) for p in self.probes_mm))
        lo, hi = (float(x) for x in self.x1d_range)
        if not 0 < lo < hi:
            raise ValueError(f"x1d range must be 0 < min < max, got {lo}, {hi}")
        set_(self, "x1d_range", (lo, hi))
        r = tuple(sorted(round_sig(float(x)) for x in self.ratio_nodes))
        if len(r) < 2 or r[0] <= 0 or len(set(r)) != len(r):
            raise ValueError(f"ratio nodes must be >= 2 distinct positive values, got {r}")
        set_(self, "ratio_nodes", r)
        if not float(self.load_max) > 0:
            raise ValueError(f"load_max must be positive, got {self.load_max}")
        set_(self, "load_max", float(self.load_max))
        if int(self.load_steps) < 3 or int(self.load_steps) != self.load_steps:
            raise ValueError(f"load_steps must be a whole number >= 3, got {self.load_steps}")
        set_(self, "load_steps", int(self.load_steps))
        if not 0 <= int(self.load_refine) <= 10 or int(self.load_refine) != self.load_refine:
            raise ValueError(f"load_refine must be a whole number in 0..10, got "
                             f"{self.load_refine}")
        set_(self, "load_refine", int(self.load_refine))
        if not float(self.x1d_ref) > 0:
            raise ValueError(f"x1d_ref must be positive, got {self.x1d_ref}")
        set_(self, "x1d_ref", float(self.x1d_ref))
        set_(self, "mesh", dict(self.mesh or {}))
        fb = self.fallback
        fb = [fb] if isinstance(fb, dict) else list(fb or [])
        set_(self, "fallback", tuple(dict(f) for f in fb))

    @property
    def load_nodes(self) -> np.ndarray:
        """The loads p / X1d of a ray (mbar/MPa)."""
        even = np.linspace(0.0, self.load_max, self.load_steps + 1)
        return np.unique(np.concatenate([even, self.onset_loads]))

    @property
    def onset_loads(self) -> np.ndarray:
        """The extra loads near 0 (ascending): the onset."""
        first = self.load_max / self.load_steps
        return first * 2.0 ** -np.arange(self.load_refine, 0, -1)

    @property
    def onset_mbar(self) -> tuple:
        """Pressures of the onset's extra nodes (at ``x1d_ref``), mbar."""
        return tuple(round_sig(float(q) * self.x1d_ref) for q in self.onset_loads)

    @property
    def pressures_mbar(self) -> tuple:
        """Pressures of the FE runs (at ``x1d_ref``), mbar."""
        return tuple(round_sig(float(q) * self.x1d_ref) for q in self.load_nodes)

    def x1d_lower(self, p_max_mbar: float) -> float:
        """Lowest X1d (MPa) searched for a curve up to ``p_max_mbar``."""
        return max(self.x1d_range[0], float(p_max_mbar) / self.load_max)

    def reach_mbar(self) -> float:
        """Highest pressure any X1d of the window can be read at (mbar)."""
        return self.load_max * self.x1d_range[1]

    @classmethod
    def from_config(cls, section: dict, study_mesh: dict | None = None,
                    study_fallback=None) -> "RaySpec":
        """From the ``scale_free_space`` section (axis forms allowed); mesh = study mesh
        updated by its ``mesh``; fallbacks = its ``mesh_fallback`` or the study's."""
        from ._grid import expand_axis

        mesh = {**(study_mesh or {}), **(section.get("mesh") or {})}
        load = section.get("load", {})
        fallback = section.get("mesh_fallback", study_fallback)
        return cls(
            probes_mm=expand_axis(section.get("probes_mm", [2, 6])),
            ratio_nodes=expand_axis(section["ratio"]),
            load_max=load["max"],
            load_steps=load.get("steps", 40),
            load_refine=load.get("refine", 0),
            x1d_range=(section["x1d_mpa"]["min"], section["x1d_mpa"]["max"]),
            x1d_ref=section.get("x1d_ref", 0.01),
            bottom=section.get("bottom", "fixed"),
            mesh=mesh,
            fallback=fallback or (),
        )

    def to_dict(self) -> dict:
        return {"probes_mm": list(self.probes_mm), "ratio_nodes": list(self.ratio_nodes),
                "load_max": self.load_max, "load_steps": self.load_steps,
                "load_refine": self.load_refine,
                "x1d_range": list(self.x1d_range), "x1d_ref": self.x1d_ref,
                "bottom": self.bottom, "mesh": dict(self.mesh),
                "fallback": [dict(f) for f in self.fallback]}


def _ray_params(spec: RaySpec, probe: float, ratio: float, cause: Cause | None, coord) -> dict:
    x1d = spec.x1d_ref
    params = {"probe_mm": probe, "bottom": spec.bottom, "x1d": round_sig(x1d),
              "x1h": round_sig(ratio * x1d)}
    if cause is not None:
        params.update({k: round_sig(v) for k, v in cause.simulate_keywords(coord, x1d).items()})
    return params


def rays_of(spec: RaySpec, cause: Cause | None = None) -> list[dict]:
    """The rays of one space: ``[{"ray_id", "probe_mm", "ratio", "coordinate", "params"}]``.

    ``cause=None`` is the neo-Hookean space (coordinate NaN).  The rays of a
    cause at its neutral coordinate are the neo-Hookean rays (same ids, same FE run).
    """
    out = []
    coords = cause.nodes if cause is not None else (math.nan,)
    for probe in spec.probes_mm:
        for ratio in spec.ratio_nodes:
            for c in coords:
                null = cause is None or c == cause.neutral
                params = _ray_params(spec, probe, ratio, None if null else cause, c)
                out.append({"ray_id": ray_id(params), "probe_mm": probe, "ratio": ratio,
                            "coordinate": c, "params": params})
    return out


#: Snakemake wildcard constraint of a bundle id.
BUNDLE_ID_PATTERN = r"[a-z][a-z0-9_]*__p[0-9.]+__r[0-9.e+-]+"


def bundle_id(model: str, probe_mm: float, ratio: float, last_ratio: float | None = None) -> str:
    """Name of the bundle of rays of one model at one probe and X1h/X1d (or a run of them).

    >>> bundle_id("pre_tension", 6.0, 0.001)
    'pre_tension__p6__r0.001'
    >>> bundle_id("neo_hookean", 2.0, 1e-4, 2.0)
    'neo_hookean__p2__r0.0001-2'
    """
    last = "" if last_ratio is None or last_ratio == ratio else f"-{_fmt(round_sig(last_ratio))}"
    return f"{model}__p{_fmt(probe_mm)}__r{_fmt(round_sig(ratio))}{last}"


def ray_bundles(spec: RaySpec, causes: dict, rays_per_job: int = 1) -> dict:
    """``{bundle_id: [ray_id, ...]}``: the FE jobs of the space.

    The rays of one (model, probe) are cut into runs of consecutive X1h/X1d of
    about ``rays_per_job`` rays (at least one X1h/X1d each): the neo-Hookean
    bundles hold the neutral rays, a cause's bundles its other nodes, so every
    ray is run once and adding a cause adds bundles without touching the others.
    A job costs about a second of start-up besides its rays (0.2-2 CPU-s each):
    a few dozen rays a job keep that small and still fill the cores to the end.

    >>> spec = RaySpec([2, 6], [0.01, 0.1, 1.0], load_max=100.0)
    >>> sorted(ray_bundles(spec, {}, rays_per_job=2))
    ['neo_hookean__p2__r0.01-0.1', 'neo_hookean__p2__r1', 'neo_hookean__p6__r0.01-0.1', 'neo_hookean__p6__r1']
    """
    out = {}
    n_ratios = len(spec.ratio_nodes)
    for name, cause in {BASELINE: None, **causes}.items():
        per_ratio = 1 if cause is None else len(cause.nodes) - 1
        chunks = max(1, min(n_ratios, math.ceil(n_ratios * per_ratio / max(1, int(rays_per_job)))))
        # consecutive runs of nearly equal length
        edges = np.linspace(0, n_ratios, chunks + 1).round().astype(int)
        runs = {spec.ratio_nodes[i]: (spec.ratio_nodes[a], spec.ratio_nodes[b - 1])
                for a, b in zip(edges[:-1], edges[1:]) for i in range(a, b)}
        for ray in rays_of(spec, cause):
            if cause is not None and ray["coordinate"] == cause.neutral:
                continue
            first, last = runs[ray["ratio"]]
            key = bundle_id(name, ray["probe_mm"], first, last)
            out.setdefault(key, []).append(ray["ray_id"])
    return out


# ------------------------------------------------------------------- ray spaces
@dataclass(eq=False)
class RaySpace:
    """Rays of one model (neo-Hookean or one cause) for every probe.

    Attributes
    ----------
    cause : Cause or None
        None for the neo-Hookean space.
    spec : RaySpec
    coordinates : ndarray (n_c,)
        Coordinates of the cause (``[nan]`` for the neo-Hookean space).
    deflection_mm : dict probe_mm -> ndarray (n_r, n_c, n_p)
        The rays (NaN where the FE run stopped).
    metadata : dict
    """

    cause: Cause | None
    spec: RaySpec
    coordinates: np.ndarray
    deflection_mm: dict
    metadata: dict = field(default_factory=dict)
    #: ThicknessNuisance per given layer thickness with an sd (see spaces_at)
    nuisance: tuple = ()

    @property
    def name(self) -> str:
        return BASELINE if self.cause is None else self.cause.name

    @property
    def probes_mm(self) -> tuple:
        return tuple(sorted(self.deflection_mm))

    def has_probe(self, probe_mm: float) -> bool:
        return any(math.isclose(probe_mm, p, abs_tol=1e-6) for p in self.deflection_mm)

    def rays(self, probe_mm: float) -> np.ndarray:
        for p, a in self.deflection_mm.items():
            if math.isclose(probe_mm, p, abs_tol=1e-6):
                return a
        raise KeyError(f"no {probe_mm:g} mm rays in the {self.name} space "
                       f"(probes: {', '.join(f'{p:g}' for p in self.probes_mm)} mm)")

    def null_slice(self) -> "RaySpace":
        """The neo-Hookean rays of this space (its neutral coordinate)."""
        if self.cause is None:
            return self
        j = int(np.argmin(np.abs(self.coordinates - self.cause.neutral)))
        return RaySpace(None, self.spec, np.array([math.nan]),
                        {p: a[:, j:j + 1] for p, a in self.deflection_mm.items()},
                        dict(self.metadata))

    def frame(self) -> pd.DataFrame:
        rows = []
        p = np.asarray(self.spec.pressures_mbar)
        for probe, a in self.deflection_mm.items():
            for i, r in enumerate(self.spec.ratio_nodes):
                for j, c in enumerate(self.coordinates):
                    rows.append(pd.DataFrame({
                        "probe_mm": probe, "ratio": r, "coordinate": c,
                        "pressure_mbar": p, "deflection_mm": a[i, j]}))
        return pd.concat(rows, ignore_index=True)


def _last_reached(rays: np.ndarray, loads: np.ndarray) -> np.ndarray:
    """Highest load with a finite deflection along the last axis (0 if none)."""
    finite = np.isfinite(rays)
    # a ray is a prefix of finite values: its reach is the last finite node
    idx = finite.shape[-1] - 1 - np.argmax(finite[..., ::-1], axis=-1)
    return np.where(finite.any(axis=-1), loads[idx], 0.0)


def coverage_frontier(space: "RaySpace") -> pd.DataFrame:
    """The highest load p/X1d each ray reached, one row per (probe, ratio, coordinate).

    Columns: ``model, probe_mm, ratio, coordinate, load_reached, load_max,
    complete, reason, mesh_fallback, ray_id``.  ``complete`` is True where the ray
    reaches ``load_max``; ``reason`` is the solver's reason where it stopped.
    """
    loads = space.spec.load_nodes
    solver = space.metadata.get("rays", {})
    ids = {(r["probe_mm"], r["ratio"], r["coordinate"] if space.cause else None): r["ray_id"]
           for r in rays_of(space.spec, space.cause)}
    rows = []
    for probe, a in sorted(space.deflection_mm.items()):
        reach = _last_reached(a, loads)
        for i, r in enumerate(space.spec.ratio_nodes):
            for j, c in enumerate(space.coordinates):
                rid = ids.get((probe, r, c if space.cause else None), "")
                info = solver.get(rid, {})
                rows.append({"model": space.name, "probe_mm": probe, "ratio": r,
                             "coordinate": c, "load_reached": float(reach[i, j]),
                             "load_max": space.spec.load_max,
                             "complete": bool(reach[i, j] >= space.spec.load_max * (1 - 1e-9)),
                             "reason": info.get("reason", ""),
                             "mesh_fallback": int(info.get("mesh_fallback", 0) or 0),
                             "ray_id": rid})
    return pd.DataFrame(rows)


def assemble_ray_space(bundle_paths, out_path, spec: RaySpec, cause: Cause | None,
                       config: dict | None = None) -> RaySpace:
    """Assemble the bundle files of one model into its space file (atomic Parquet).

    Every ray of :func:`rays_of` must be in one of ``bundle_paths`` (extra rays
    are ignored); rays that stopped early keep their NaN tail, and the coverage
    frontier (:func:`coverage_frontier`) goes into the metadata.
    """
    from skinsuction.provenance import collect

    by_id, solver = {}, {}
    for path in bundle_paths:
        frame, meta = _read_parquet(path)
        for rid, g in frame.groupby("ray_id", sort=False):
            by_id[rid] = g
            solver[rid] = (meta.get("rays") or {}).get(rid, {})
    p = np.asarray(spec.pressures_mbar)
    rays = rays_of(spec, cause)
    coords = np.array(cause.nodes if cause is not None else [math.nan])
    arrays = {probe: np.full((len(spec.ratio_nodes), coords.size, p.size), np.nan)
              for probe in spec.probes_mm}
    name = cause.name if cause else BASELINE
    for ray in rays:
        frame = by_id.get(ray["ray_id"])
        if frame is None:
            raise ValueError(f"ray {ray['ray_id']} of the {name} space is missing from the "
                             "inputs")
        fp = frame["pressure_mbar"].to_numpy(float)
        if fp.shape != p.shape or not np.allclose(fp, p):
            raise ValueError(f"ray {ray['ray_id']}: pressures differ from the specification "
                             "(rebuild the rays)")
        i = spec.ratio_nodes.index(ray["ratio"])
        j = 0 if cause is None else cause.nodes.index(ray["coordinate"])
        arrays[ray["probe_mm"]][i, j] = frame["deflection_mm"].to_numpy(float)
    ray_info = {r["ray_id"]: solver[r["ray_id"]] for r in rays}
    n_failed = sum(1 for r in ray_info.values() if not r.get("converged", False))
    space = RaySpace(cause, spec, coords, arrays, {"rays": ray_info})
    frontier = coverage_frontier(space)
    meta = collect(config=config, space=name,
                   cause=cause.to_dict() if cause else None, ray_spec=spec.to_dict(),
                   n_rays=len(rays), n_stopped=n_failed, rays=ray_info,
                   coverage=frontier.drop(columns=["reason"]).to_dict(orient="records"))
    space = RaySpace(cause, spec, coords, arrays, meta)
    _write_parquet(space.frame(), out_path, meta)
    log.info("%s space: %d rays (%d stopped early) -> %s", name, len(rays), n_failed, out_path)
    return space


def read_ray_space(path) -> RaySpace:
    """Read a space written by :func:`assemble_ray_space`."""
    frame, meta = _read_parquet(path)
    if "ray_spec" not in meta or "load_max" not in meta["ray_spec"]:
        raise ValueError(f"{path}: not a scale-free simulated space (rebuild it with the "
                         "workflow)")
    spec = RaySpec(**meta["ray_spec"])
    cause = Cause.from_dict(meta["cause"]) if meta.get("cause") else None
    coords = np.array(cause.nodes if cause is not None else [math.nan])
    p = np.asarray(spec.pressures_mbar)
    arrays = {}
    for probe, g in frame.groupby("probe_mm"):
        a = np.full((len(spec.ratio_nodes), coords.size, p.size), np.nan)
        i = np.searchsorted(np.asarray(spec.ratio_nodes), g["ratio"].to_numpy(float))
        j = (np.zeros(len(g), int) if cause is None
             else np.searchsorted(coords, g["coordinate"].to_numpy(float)))
        k = np.searchsorted(p, g["pressure_mbar"].to_numpy(float))
        a[i, j, k] = g["deflection_mm"].to_numpy(float)
        arrays[float(probe)] = a
    return RaySpace(cause, spec, coords, arrays, meta)


def read_ray_spaces(space_dir) -> dict:
    """All spaces of a scale-free space directory: ``{name: RaySpace}``.

    The neo-Hookean one is needed.  Raises :class:`SpaceMissingError` with the
    command that builds them if the directory or the neo-Hookean space is missing.
    """
    d = Path(space_dir)
    if d.is_file() and d.suffix == ".parquet":
        d = d.parent
    hint = ("build it with the workflow: `snakemake --cores 2 scale_free_space` "
            "(or `--configfile config/ci.yaml --replace-workflow-config` for a coarse one)")
    if not d.is_dir():
        raise SpaceMissingError(f"{d}: no such directory of the scale-free space; {hint}")
    spaces = {}
    for path in sorted(d.glob("*.parquet")):
        try:
            s = read_ray_space(path)
        except Exception as err:  # pyarrow raises many types for a bad file
            raise SpaceFileError(f"{path}: not a scale-free space ({type(err).__name__}: "
                                 f"{' '.join(str(err).split())[:200]})") from None
        spaces[s.name] = s
    if BASELINE not in spaces:
        raise SpaceMissingError(f"{d}: no {BASELINE}.parquet (the neo-Hookean rays); {hint}")
    return spaces


# ------------------------------------------------------------------ interpolation
