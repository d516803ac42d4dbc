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
recorded (:func:`skinsuction.space.coverage_frontier`).

This module says which rays a space has: their names (:func:`ray_id`), the
specification (:class:`RaySpec`), the rays of each model (:func:`rays_of`) and
the FE jobs that run them (:func:`ray_bundles`).  The rays stored and read
back are :mod:`._ray_space`'s; solved, :mod:`._ray_solve`'s; interpolated,
:mod:`._ray_interpolate`'s:

* across rays, cubic Lagrange in ``log10 r`` and in the cause's axis
  coordinate (:meth:`Cause.to_axis`), applied to ``log M`` (the deflection
  varies by decades over r; its logarithm is close to a smooth sigmoid in
  log r), at the ray loads;
* then along the load of the ray, cubic Lagrange on log M in log ``q``
  (:class:`skinsuction.space.LoadAxis`; on M in q below the first load > 0).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ._causes import BASELINE, Cause
from ._storage import (
    AXES,
    POINT_ID_PATTERN,
    SIGNIFICANT_DIGITS,
    _fmt,
    parse_point_id,
    point_id,
    round_sig,
)

__all__ = ["RaySpec", "ray_id", "parse_ray_id", "RAY_ID_PATTERN", "EXTRA_KEYWORDS", "rays_of",
           "ray_bundles", "bundle_id", "BUNDLE_ID_PATTERN"]

#: Extra keywords of the model beyond the grid axes of a point id, with defaults.
EXTRA_KEYWORDS = {"prestretch": 1.0}

#: Snakemake wildcard constraint of a ray id.
RAY_ID_PATTERN = POINT_ID_PATTERN + r"(?:__[a-z][a-z0-9_]*=[^/_]+)*"


# ------------------------------------------------------------------------ ray ids
def ray_id(params: dict) -> str:
    """Name of one FE ray: the point id plus ``__keyword=value`` for extra keywords.

    Extra keywords (``prestretch``) at their default value are left out, so a
    neo-Hookean ray has the plain point id.

    Parameters
    ----------
    params : dict
        The ray's grid-point keywords (:data:`skinsuction.space.AXES`; the missing
        ones at their defaults) and extra keywords (:data:`EXTRA_KEYWORDS`).

    Returns
    -------
    str

    Examples
    --------
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
    """The model keywords of a ray id (inverse of :func:`ray_id`), extras included.

    Parameters
    ----------
    rid : str
        A ray id.

    Returns
    -------
    dict
        The keywords of :data:`skinsuction.space.AXES` and of :data:`EXTRA_KEYWORDS`.
    """
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
    load_tail_from : float
        Where the tail starts (mbar/MPa; 0: no tail).  With a tail the
        ``load_steps`` even steps end there and ``load_tail_steps`` steps spaced
        evenly in log q run on to ``load_max``: M(q) is smooth at large loads, so
        a 500 mbar reach on soft skin costs 16 nodes, not 120 even ones (a
        cubic read within 0.13 %, ``docs/scale_free_space.md``).
    load_tail_steps : int
        Steps of the tail (0: none).
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
    load_tail_from: float = 0.0
    load_tail_steps: int = 0

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
        tail_from, tail_steps = float(self.load_tail_from), int(self.load_tail_steps)
        if tail_steps != self.load_tail_steps or tail_steps < 0 or (
                tail_steps and not 0 < tail_from < self.load_max) or (
                not tail_steps and tail_from):
            raise ValueError(f"the load tail needs steps >= 1 from 0 < from < load_max "
                             f"({self.load_max:g}), got from {self.load_tail_from}, steps "
                             f"{self.load_tail_steps}")
        set_(self, "load_tail_from", tail_from)
        set_(self, "load_tail_steps", tail_steps)
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
        even = np.linspace(0.0, self.even_max, self.load_steps + 1)
        tail = self.even_max * (self.load_max / self.even_max) ** (
            np.arange(1, self.load_tail_steps + 1) / max(self.load_tail_steps, 1))
        return np.unique(np.concatenate([even, tail, self.onset_loads]))

    @property
    def even_max(self) -> float:
        """Where the even load steps end: the tail's start, else ``load_max``."""
        return self.load_tail_from if self.load_tail_steps else self.load_max

    @property
    def fallback_below_mbar(self) -> float | None:
        """The fallback meshes run for a ray that stops below this pressure (at
        ``x1d_ref``): the tail's start, None without a tail.  In the tail a
        neo-Hookean dermis stops for want of an equilibrium (stretches of 4-13, no
        skin's), and a fallback solve from 0 would double those rays' cost for a
        few per cent more load; a stiffening dermis's rays get the fallback
        anywhere (:func:`compute_ray`)."""
        return self.even_max * self.x1d_ref if self.load_tail_steps else None

    def untailed(self) -> "RaySpec":
        """The same rays without the tail, to its start (the geometry spaces' rays).

        Examples
        --------
        >>> spec = RaySpec([2], [0.01, 1.0], load_max=71400, load_steps=48,
        ...                load_tail_from=20000, load_tail_steps=16)
        >>> len(spec.load_nodes), spec.untailed().load_max, len(spec.untailed().load_nodes)
        (65, 20000.0, 49)
        """
        from dataclasses import replace
        if not self.load_tail_steps:
            return self
        return replace(self, load_max=self.load_tail_from, load_tail_from=0.0,
                       load_tail_steps=0)

    @property
    def onset_loads(self) -> np.ndarray:
        """The extra loads near 0 (ascending): the onset."""
        first = self.even_max / self.load_steps
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
        """Lowest X1d (MPa) searched for a curve up to ``p_max_mbar``.

        Parameters
        ----------
        p_max_mbar : float
            The highest pressure of the curve (mbar).

        Returns
        -------
        float
        """
        return max(self.x1d_range[0], float(p_max_mbar) / self.load_max)

    def reach_mbar(self) -> float:
        """Highest pressure any X1d of the window can be read at (mbar).

        Returns
        -------
        float
        """
        return self.load_max * self.x1d_range[1]

    @classmethod
    def from_config(cls, section: dict, study_mesh: dict | None = None,
                    study_fallback=None) -> "RaySpec":
        """The specification of the ``scale_free_space`` section of the configuration.

        Parameters
        ----------
        section : dict
            The section (axis forms allowed, :func:`skinsuction.space.expand_axis`).
        study_mesh : dict, optional
            The study's ``mesh``, updated by the section's own ``mesh``.
        study_fallback : dict or list of dict, optional
            The study's ``mesh_fallback``, used where the section has none.

        Returns
        -------
        RaySpec
        """
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
            load_tail_from=(load.get("tail") or {}).get("from", 0.0),
            load_tail_steps=(load.get("tail") or {}).get("steps", 0),
            x1d_range=(section["x1d_mpa"]["min"], section["x1d_mpa"]["max"]),
            x1d_ref=section.get("x1d_ref", 0.01),
            bottom=section.get("bottom", "fixed"),
            mesh=mesh,
            fallback=fallback or (),
        )

    def to_dict(self) -> dict:
        """The specification as plain JSON-able values (``RaySpec(**d)`` reads it back).

        Returns
        -------
        dict
        """
        return {"probes_mm": list(self.probes_mm), "ratio_nodes": list(self.ratio_nodes),
                "load_max": self.load_max, "load_steps": self.load_steps,
                "load_refine": self.load_refine,
                "x1d_range": list(self.x1d_range), "x1d_ref": self.x1d_ref,
                "bottom": self.bottom, "mesh": dict(self.mesh),
                "fallback": [dict(f) for f in self.fallback],
                # only with a tail: the specifications of spaces built before it read alike
                **({"load_tail_from": self.load_tail_from,
                    "load_tail_steps": self.load_tail_steps} if self.load_tail_steps else {})}


def _ray_params(spec: RaySpec, probe: float, ratio: float, cause: Cause | None, coord,
                layers=None, digits: int = SIGNIFICANT_DIGITS) -> dict:
    """The model keywords of one ray: at ``X1d = x1d_ref``, on ``layers`` (``{"t_d": mm,
    "t_h": mm}``; default the paper's, left out), the cause's value at ``coord``
    rounded to ``digits`` (a thickness cause replaces its layer)."""
    x1d = spec.x1d_ref
    params = {"probe_mm": probe, "bottom": spec.bottom, "x1d": round_sig(x1d),
              "x1h": round_sig(ratio * x1d), **(layers or {})}
    if cause is not None:
        params.update({k: round_sig(v, digits)
                       for k, v in cause.simulate_keywords(coord, x1d).items()})
    return params


def rays_of(spec: RaySpec, cause: Cause | None = None) -> list[dict]:
    """The rays of one space.

    The rays of a cause at its neutral coordinate are the neo-Hookean rays (same
    ids, same FE run).

    Parameters
    ----------
    spec : RaySpec
    cause : Cause, optional
        None: the neo-Hookean space (coordinate NaN).

    Returns
    -------
    list of dict
        ``{"ray_id", "probe_mm", "ratio", "coordinate", "params"}`` per ray, by
        probe, then X1h/X1d, then coordinate.
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

    Parameters
    ----------
    model : str
        ``neo_hookean`` or a cause's name.
    probe_mm : float
    ratio : float
        The (first) X1h/X1d of the bundle.
    last_ratio : float, optional
        The last X1h/X1d of a run of them.

    Returns
    -------
    str

    Examples
    --------
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

    Parameters
    ----------
    spec : RaySpec
    causes : dict
        ``{name: Cause}``; the neo-Hookean bundles are always there.
    rays_per_job : int
        About how many rays a bundle holds.

    Returns
    -------
    dict
        ``{bundle_id: [ray_id, ...]}``.

    Examples
    --------
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
