"""Every probe and the subject's own layers: the spaces of one measurement.

The scale-free space holds rays of the Cutometer probes (2, 4, 6 and 8 mm) for the
paper's layers (1 mm each).  A measurement with another aperture, or its own layer
thicknesses (ultrasound, OCT), gets its neo-Hookean rays from
:class:`skinsuction.space.OnDemandRays`: read off the geometry space where its error
estimate allows, solved by FE elsewhere (docs/geometry.md).

The causes get their rays at that geometry too (:func:`spaces_at`): off their own
geometry spaces or solved, only the X1h/X1d nodes in a window around the neo-Hookean
fit (``ratio_window``, :func:`window_nodes`).  Without a solver a cause's effect on
log M is carried over from the probes and layers it was simulated for, an
approximation the notes name.  A given thickness with an sd becomes a nuisance
parameter of every fit (:class:`ThicknessNuisance`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from skinsuction.measured import DEFAULT_LAYERS_MM, Geometry

from ._causes import BASELINE
from ._lagrange import LagrangeAxis
from ._on_demand import OnDemandRays
from ._ray_space import RaySpace
from ._storage import AXIS_PATHS

__all__ = ["GeometryOutsideSpace", "spaces_at", "ThicknessNuisance", "window_nodes",
           "THICKNESS_RESOLUTION_MM"]

#: Thicknesses are rounded to this (mm) before rays are solved for them: a
#: measured thickness is not known better, and rounded geometries share a cache.
THICKNESS_RESOLUTION_MM = 0.01


class GeometryOutsideSpace(ValueError):
    """A probe and layers the spaces do not cover (and no on-demand solver is allowed)."""


def _round_mm(x: float) -> float:
    return round(round(float(x) / THICKNESS_RESOLUTION_MM) * THICKNESS_RESOLUTION_MM, 6)


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
        """Name of the thickness in reports (``t_d``, ``t_h``)."""
        return self.keyword

    def thickness(self, delta):
        """Thickness of an offset in sd units.

        Parameters
        ----------
        delta : float or array_like
            Offsets from :attr:`value`, in units of :attr:`sd`.

        Returns
        -------
        float or ndarray
            Thicknesses (mm).
        """
        return self.value + np.asarray(delta, dtype=float) * self.sd




def _cause_effect(space, probe_mm: float):
    """log M_c - log M_neutral of a cause's rays at one aperture, (n_r, n_c, n_p - 1).

    Interpolated across the cause's probes (cubic Lagrange in log10 of the
    aperture); exactly 0 at the neutral coordinate; None outside its probes.
    """
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
    """The X1h/X1d nodes within a window, at least 4 (a cubic stencil).

    Parameters
    ----------
    nodes : sequence of float
        The ascending X1h/X1d nodes of a ray specification.
    window : (float, float), optional
        ``(lo, hi)``; None: every node.

    Returns
    -------
    tuple of float
        The nodes inside, widened alternately up and down to at least 4.

    Examples
    --------
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



#: A fit reads a ray no higher than this times the largest measured deflection: a
#: candidate whose curve runs twice as high as the data is no fit of it.
FIT_REACH = 2.0


def fit_reach_mm(curves) -> dict:
    """``{probe: mm}``: the largest deflection a fit of the measured ``curves`` reads
    under each probe, :data:`FIT_REACH` times the largest one measured there.

    Parameters
    ----------
    curves : iterable
        Objects with ``probe_mm`` and ``deflection_mm`` (a measurement's curves).

    Examples
    --------
    >>> from types import SimpleNamespace as C
    >>> fit_reach_mm([C(probe_mm=2, deflection_mm=[0, 0.1, 0.25]),
    ...               C(probe_mm=6, deflection_mm=[0, 0.9])])
    {2.0: 0.5, 6.0: 1.8}
    """
    out = {}
    for c in curves:
        m = np.asarray(c.deflection_mm, dtype=float)
        top = float(np.nanmax(m)) if np.isfinite(m).any() else math.nan
        p = float(c.probe_mm)
        if math.isfinite(top):
            out[p] = max(out.get(p, 0.0), FIT_REACH * top)
    return out


def spaces_at(spaces: dict, probes, geometry: Geometry, on_demand: OnDemandRays | None = None,
              solve_causes: bool = True, ratio_window=None, reads_up_to_mm=None):
    """The ray spaces of one measurement: every model at its probes and layers.

    Parameters
    ----------
    spaces : dict name -> RaySpace
        As read by :func:`skinsuction.space.read_ray_spaces`.
    probes : iterable of float
        Apertures (mm) of the measurement.
    geometry : Geometry
        The measurement's layer thicknesses, given or assumed, with their sd.
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
    reads_up_to_mm : dict probe -> float, optional
        The largest deflection (mm) a fit of the measurement can read under each
        probe (:func:`fit_reach_mm`): rays read off a geometry space are solved
        where their error estimate exceeds the tolerance below it only
        (:meth:`OnDemandRays.rays`).  Default: at any deflection.

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
    base = spaces[BASELINE]
    at = _Measurement([float(p) for p in probes], geometry, base, on_demand,
                      reads_up_to_mm=dict(reads_up_to_mm or {}))
    rays = _neo_hookean_rays(at)
    meta = {**base.metadata, "geometry": geometry.to_dict()}
    out = {BASELINE: RaySpace(None, at.spec, np.array([math.nan]), rays, meta)}
    own_brackets = set()  # causes solved at these layers: thickness brackets of their own
    for name, space in spaces.items():
        if name == BASELINE:
            continue
        cause = space.cause
        if cause.geometric and cause.keyword in geometry.given:
            at.notes.append(f"{name}: not a free cause, the {cause.symbol} is given "
                            f"({getattr(geometry, cause.keyword):g} mm)")
        elif at.default and all(space.has_probe(p) for p in at.probes):
            out[name] = RaySpace(cause, at.spec, space.coordinates,
                                 {p: at.cut(space.rays(p)) for p in at.probes}, space.metadata)
        elif on_demand is not None and solve_causes:
            out[name] = _solved_cause(name, space, at, ratio_window)
            own_brackets.add(name)
        else:
            carried = _carried_cause(name, space, at, rays)
            if carried is not None:
                out[name] = carried
    _attach_nuisances(out, own_brackets, at)
    return out, at.notes


@dataclass
class _Measurement:
    """What the spaces of one measurement are taken at, and the notes they gather.

    ``layers``: the layers the rays are solved for (given ones rounded), by
    parameter path (``{"dermis.thickness": mm, "hypodermis.thickness": mm}``);
    ``spec``: the ray specification at the measurement's probes."""

    probes: list
    geometry: Geometry
    #: the space's neo-Hookean rays
    base: RaySpace
    on_demand: OnDemandRays | None
    notes: list = field(default_factory=list)
    #: probe -> the largest deflection a fit reads (mm), see :func:`spaces_at`
    reads_up_to_mm: dict = field(default_factory=dict)

    def __post_init__(self):
        self.layers = _rounded_layers(self.geometry, self.notes)
        # rays on demand and the geometry spaces stop where the load tail starts: a
        # measurement with any of them takes the untailed loads (a prefix of the tailed
        # ones), the space's own rays cut to them; the tail only where every probe's
        # rays are the space's own
        own = self.default and all(self.base.has_probe(p) for p in self.probes)
        spec = self.base.spec if own else self.base.spec.untailed()
        self.spec = replace(spec, probes_mm=tuple(self.probes))
        self.n_loads = len(self.spec.pressures_mbar)

    def reach(self, p) -> dict:
        """``{"reads_up_to_mm": mm}`` for a solver's call at probe ``p``, if known."""
        v = self.reads_up_to_mm.get(p)
        return {} if v is None else {"reads_up_to_mm": v}

    def cut(self, rays: np.ndarray) -> np.ndarray:
        """The space's own rays (…, n_p) cut to this measurement's loads."""
        return rays[..., :self.n_loads]

    @property
    def default(self) -> bool:
        return self.geometry.is_default

    def where(self) -> str:
        """The layers, for notes and errors."""
        return (f"t_d = {self.layers[AXIS_PATHS['t_d']]:g}, "
                f"t_h = {self.layers[AXIS_PATHS['t_h']]:g} mm")


def _rounded_layers(geometry: Geometry, notes: list) -> dict:
    """The layers the rays are solved for, by parameter path: given ones rounded to
    THICKNESS_RESOLUTION_MM."""
    t_d, t_h = geometry.t_d, geometry.t_h
    if not geometry.is_default:
        t_d, t_h = _round_mm(t_d), _round_mm(t_h)
        if abs(t_d - geometry.t_d) > 1e-9 or abs(t_h - geometry.t_h) > 1e-9:
            notes.append(f"thicknesses rounded to {THICKNESS_RESOLUTION_MM:g} mm for the FE "
                         f"rays: t_d = {t_d:g}, t_h = {t_h:g} mm")
    return {AXIS_PATHS["t_d"]: t_d, AXIS_PATHS["t_h"]: t_h}


def _neo_hookean_rays(at: _Measurement) -> dict:
    """``{probe: rays}`` of the neo-Hookean model at the measurement's probes and layers:
    the space's own where it has them, else solved on demand (noted)."""
    base, rays, solved = at.base, {}, []
    for p in at.probes:
        if at.default and base.has_probe(p):
            rays[p] = at.cut(base.rays(p))
            continue
        if at.on_demand is None:
            raise GeometryOutsideSpace(
                f"no neo-Hookean rays of the {p:g} mm probe for {at.where()} "
                f"in the space (it has {', '.join(f'{q:g}' for q in base.probes_mm)} mm with "
                "1 mm layers); allow solving them on demand")
        rays[p], info = at.on_demand.rays(p, at.layers, **at.reach(p))
        solved.append((p, info))
    for p, info in solved:
        where = "" if info["cache"] == "geometry space" else f"; cached in {info['cache']}"
        at.notes.append(f"neo-Hookean rays of the {p:g} mm probe at {at.where()}"
                        f" {_source(info)} ({info['rays']} rays, {info['stopped_early']} "
                        f"stopped early{where})")
    return rays


def _source(info: dict) -> str:
    """Where rays on demand came from, for the notes: the geometry space, solved, or both."""
    read = info.get("rays_interpolated", 0)
    if not read:
        return "solved on demand"
    solved = info.get("rays_solved", 0)
    return ("read off the geometry space" + (
        f" ({solved} solved on demand where its error estimate exceeded the tolerance)"
        if solved else ""))


def _solved_cause(name: str, space: RaySpace, at: _Measurement, ratio_window) -> RaySpace:
    """A cause's space at the measurement: its rays at these probes and layers, solved
    on demand (its own where the space has them), at the X1h/X1d nodes of the window."""
    full = at.base.spec.ratio_nodes
    nodes = window_nodes(full, ratio_window)
    keep = [full.index(r) for r in nodes]
    arrays, total = {}, {"rays": 0, "stopped_early": 0, "rays_interpolated": 0,
                         "rays_solved": 0}
    for p in at.probes:
        if at.default and space.has_probe(p):
            arrays[p] = at.cut(space.rays(p)[keep])
            continue
        arrays[p], info = at.on_demand.rays(p, at.layers, space.cause, **_subset(nodes, full),
                                            **at.reach(p))
        for k in total:
            total[k] += info.get(k, 0)
    window = ("" if len(nodes) == len(full) else
              f", X1h/X1d {nodes[0]:g}-{nodes[-1]:g} only ({len(nodes)} of "
              f"{len(full)} nodes)")
    at.notes.append(f"{name}: its rays at this geometry {_source(total)} ({total['rays']} "
                    f"rays, {total['stopped_early']} stopped early{window})")
    return RaySpace(space.cause, replace(at.spec, ratio_nodes=nodes),
                    np.asarray(space.cause.nodes, dtype=float), arrays,
                    {**space.metadata, "geometry": at.geometry.to_dict()})


def _carried_cause(name: str, space: RaySpace, at: _Measurement, rays: dict):
    """A cause's space at the measurement without its own rays there: its effect on
    log M, where it was simulated, on the neo-Hookean ``rays`` (an approximation the
    notes name); None (noted) if it was not simulated for apertures around these."""
    arrays = {}
    for p in at.probes:
        effect = _cause_effect(space, p)
        if effect is None:
            break
        with np.errstate(divide="ignore", invalid="ignore"):
            g = (np.log(np.where(rays[p][..., 1:] > 0, rays[p][..., 1:], np.nan))
                 + effect[..., :rays[p].shape[-1] - 1])  # the cause's loads, cut to the rays'
        full = np.zeros(g.shape[:-1] + (g.shape[-1] + 1,))
        full[..., 1:] = np.exp(g)
        arrays[p] = full
    if len(arrays) < len(at.probes):
        at.notes.append(f"{name}: simulated for the {', '.join(f'{q:g}' for q in space.probes_mm)}"
                        f" mm probes only, not {', '.join(f'{q:g}' for q in at.probes)} mm")
        return None
    where = []
    if not at.default:
        where.append(f"{DEFAULT_LAYERS_MM[0]:g} mm + {DEFAULT_LAYERS_MM[1]:g} mm layers")
    if any(not space.has_probe(p) for p in at.probes):
        where.append(f"the {', '.join(f'{q:g}' for q in space.probes_mm)} mm probes")
    at.notes.append(f"{name}: its effect on the deflection was simulated for "
                    f"{' and '.join(where)} and is carried over to this measurement "
                    "(an approximation)")
    return RaySpace(space.cause, at.spec, space.coordinates, arrays,
                    {**space.metadata, "geometry": at.geometry.to_dict()})


def _attach_nuisances(out: dict, own_brackets: set, at: _Measurement) -> None:
    """Give every space the thickness nuisances of the given layers with an sd: the
    neo-Hookean brackets, or a cause's own where its rays were solved at these layers."""
    nuisance = _nuisances(out[BASELINE], at, at.notes)
    for name, space in out.items():
        space.nuisance = nuisance
        if nuisance and name in own_brackets:
            space.nuisance = _nuisances(space, at, [], at.base.spec.ratio_nodes)
    if nuisance and own_brackets:
        at.notes.append(f"{', '.join(sorted(own_brackets))}: the thickness nuisance moves each "
                        "cause's curve by its own rays at ±1 sd (read or solved)")


def _subset(nodes, full) -> dict:
    """``{"ratio_nodes": nodes}`` if they are fewer than the ``full`` nodes, else
    nothing: a solver is asked for a cut window only."""
    return {"ratio_nodes": tuple(nodes)} if len(nodes) < len(full) else {}


def _nuisances(center, at: _Measurement, notes, full_nodes=()) -> tuple:
    """A :class:`ThicknessNuisance` per given thickness with an sd (rays on demand):
    brackets of ``center``'s own model (neo-Hookean, or a cause at every node) at
    the measurement's layers (by path) with that thickness moved by -1 and +1 sd."""
    probes, geometry, layers, on_demand = at.probes, at.geometry, at.layers, at.on_demand
    cause = center.cause
    coordinates = np.array([math.nan]) if cause is None else np.asarray(cause.nodes, float)
    out = []
    for key in ("t_d", "t_h"):
        sd = (geometry.sd or {}).get(key)
        if key not in geometry.given or not sd:
            continue
        if on_demand is None:
            notes.append(f"the {key} sd ({sd:g} mm) is not used: its rays would be solved on "
                         "demand, which is not allowed")
            continue
        value = layers[AXIS_PATHS[key]]
        brackets, total = [], {"rays_interpolated": 0, "rays_solved": 0}
        for t in (value - sd, value + sd):
            t = max(_round_mm(t), THICKNESS_RESOLUTION_MM)
            other = {**layers, AXIS_PATHS[key]: t}
            rays = {}
            for p in probes:  # a stand-in for the FE (tests) solves every bracket
                kw = {**_subset(center.spec.ratio_nodes, full_nodes), **at.reach(p)}
                rays[p], info = (on_demand.moved_rays(p, layers, other, at.cut(center.rays(p)),
                                                      cause, **kw)
                                 if isinstance(on_demand, OnDemandRays)
                                 else on_demand.rays(p, other, cause, **kw))
                if not info.get("rays_interpolated", 0):  # solved whole, or read from the cache
                    info = {**info, "rays_solved": info.get("rays", 0)}
                for k in total:
                    total[k] += info.get(k, 0)
            # rays on demand stop where the load tail starts: at 1 mm layers the centre
            # (the shipped rays) has the tail, its brackets do not
            brackets.append(RaySpace(cause, center.spec.untailed(), coordinates, rays,
                                     {**center.metadata, key: t}))
        out.append(ThicknessNuisance(key, value, float(sd), center, *brackets))
        notes.append(f"the given {key} = {value:g} ± {sd:g} mm is a nuisance parameter of every "
                     f"fit (Gaussian prior; neo-Hookean rays at ±1 sd {_source(total)})")
    return tuple(out)
