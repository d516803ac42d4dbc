"""Open a simulated space in either layout, as one space per probe.

The identification and the diagnosis never ask which layout a space has: the
paper's grid (:class:`GriddedSpace`) and the scale-free rays
(:class:`NeoHookeanSlice`) both offer what :class:`ProbeSpace` lists.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from pathlib import Path

from skinsuction._files import file_sha256
from skinsuction.errors import InputError
from skinsuction.measured import Geometry

from ._causes import BASELINE
from ._geometry import GeometryOutsideSpace, spaces_at
from ._geometry_files import geometry_file_for
from ._grid import read_space
from ._interpolate import GriddedSpace
from ._on_demand import OnDemandRays
from ._probe_space import ProbeSpace
from ._neo_hookean_slice import NeoHookeanSlice
from ._ray_space import read_ray_space, read_ray_spaces
from ._shipped import resolve_space

__all__ = ["ProbeSpace", "LoadedSpace", "load_space", "APERTURE_RANGE_MM"]

#: Apertures (mm) the scale-free space accepts (rays of others are solved on demand).
APERTURE_RANGE_MM = (1.0, 12.0)

#: Geometries whose slices one process keeps (least recently used dropped): a slice
#: tabulated for a protocol holds ~60 MB a probe, and a study reads a few geometries
#: a subject (its thickness +-1 sd, the preferred one), thousands in a study.
GEOMETRIES_KEPT = 8


def _is_scale_free(path: Path) -> bool:
    if path.is_dir():
        return True
    try:
        import json

        import pyarrow.parquet as pq

        meta = pq.read_schema(path).metadata or {}
        return "ray_spec" in json.loads(meta.get(b"skinsuction", b"{}"))
    except Exception:  # a bad file is reported by the reader below
        return False


def _read_scale_free(path: Path, bottom):
    """The neo-Hookean scale-free space: ({probe: NeoHookeanSlice}, metadata, reach)."""
    try:
        space = (read_ray_space(path) if path.is_file()
                 else read_ray_spaces(path)[BASELINE])
    except FileNotFoundError as err:
        raise InputError(str(err)) from None
    except Exception as err:  # pyarrow raises many types for a bad file
        raise InputError(f"{path}: not a scale-free simulated space "
                         f"({type(err).__name__}: {' '.join(str(err).split())[:200]})") from None
    if space.spec.bottom != bottom:
        raise InputError(f"{path}: the scale-free space has bottom {space.spec.bottom!r}, "
                         f"not {bottom!r}")
    slices = {p: NeoHookeanSlice(space, p) for p in space.probes_mm}
    return slices, space.metadata, (0.0, space.spec.reach_mbar()), space


def _read_space(space_path, bottom):
    """The simulated space: ({probe: GriddedSpace or NeoHookeanSlice}, metadata, range)."""
    path = Path(space_path)
    if not path.exists():
        raise InputError(f"{path}: simulated space not found (build it with the workflow, "
                         "e.g. `snakemake --cores 2 scale_free_space`)")
    if _is_scale_free(path):
        return _read_scale_free(path, bottom)
    try:
        space = read_space(path)
        slices = space.slices()
    except Exception as err:  # pyarrow raises many types for a bad file
        raise InputError(f"{path}: not a simulated-space database "
                         f"({type(err).__name__}: {' '.join(str(err).split())[:200]})") from None
    sel = slices[slices["bottom"] == bottom]
    if sel.empty:
        raise InputError(f"{path}: no points with bottom condition {bottom!r} "
                         f"(available: {sorted(set(slices['bottom']))})")
    spaces = {}
    for probe in sorted(set(sel["probe_mm"].astype(float))):
        try:
            spaces[probe] = GriddedSpace.from_space(space, probe, bottom=bottom)
        except ValueError as err:
            raise InputError(f"{path}: the {probe:g} mm space is not a usable grid ({err})") from None
    p_range = (max(float(s.pressure_mbar[0]) for s in spaces.values()),
               min(float(s.pressure_mbar[-1]) for s in spaces.values()))
    return spaces, space.metadata, p_range, None




class LoadedSpace:
    """A simulated space read once for many identifications (a study).

    Parameters
    ----------
    spaces : dict
        Probe (mm) -> the space of that probe in either layout (a
        :class:`GriddedSpace` or a :class:`NeoHookeanSlice`: both are
        :class:`ProbeSpace`).
    info : dict
        Describes the file for the outputs (path, SHA-256, source, ...).
    p_range : (float, float), optional
        Pressures (mbar) a curve may span; None: each probe's own.
    bottom : str
        Bottom condition of the curves.
    rays : RaySpace, optional
        The neo-Hookean ray space of a scale-free space (None for a grid).
    geometry : Geometry, optional
        The measurement's layers (default: the paper's 1 mm each).
    on_demand : OnDemandRays, optional
        Solver of rays for a probe or layers the scale-free space lacks (None:
        refused).
    """

    def __init__(self, spaces: dict, info: dict, p_range=None, bottom: str = "fixed",
                 rays=None, geometry: Geometry | None = None, on_demand=None, _shared=None):
        self.spaces, self.info, self._p_range, self.bottom = spaces, info, p_range, bottom
        #: the neo-Hookean ray space of a scale-free space (None for a grid)
        self.rays = rays
        self.geometry = geometry or Geometry()
        #: solver of rays for a probe or layers the scale-free space lacks (None: refused)
        self.on_demand = on_demand
        # the causes' spaces, and slices by geometry (the GEOMETRIES_KEPT last used)
        self._shared = {"geometries": OrderedDict()} if _shared is None else _shared
        self.reads_up_to_mm = {}  # probe -> how high a fit reads (mm), see :meth:`at`

    @classmethod
    def given(cls, spaces: dict, bottom: str = "fixed") -> "LoadedSpace":
        """A space built in memory (no file).

        Parameters
        ----------
        spaces : dict
            Probe (mm) -> :class:`ProbeSpace`.
        bottom : str

        Returns
        -------
        LoadedSpace
        """
        return cls(spaces, {"path": None, "sha256": None, "name": "given in memory"},
                   None, bottom)

    @property
    def available_probes(self):
        """Probes (mm) a measured file may hold: those of a grid; any for rays (None)."""
        return None if self.rays is not None else list(self.spaces)

    def at(self, geometry: Geometry, reads_up_to_mm=None) -> "LoadedSpace":
        """This space for a measurement with its own layers (shares its caches).

        Parameters
        ----------
        geometry : Geometry
        reads_up_to_mm : dict probe -> float, optional
            How high a fit of the measurement reads (:func:`fit_reach_mm`, passed to
            :func:`spaces_at`).  Default: this space's (none: at any deflection).

        Returns
        -------
        LoadedSpace
        """
        out = LoadedSpace(self.spaces, self.info, self._p_range, self.bottom, self.rays,
                          geometry, self.on_demand, self._shared)
        out.reads_up_to_mm = dict(self.reads_up_to_mm if reads_up_to_mm is None
                                  else reads_up_to_mm)
        return out

    def notes(self, probes) -> list:
        """What the geometry of :meth:`probe` assumed or solved, for the outputs.

        Parameters
        ----------
        probes : iterable of float
            The probes (mm) asked for.

        Returns
        -------
        list of str
            Each note once.
        """
        out = []
        kept = self._shared["geometries"].get(self._geometry_key(), {})
        for p in probes:
            for n in kept.get(("notes", float(p)), []):
                if n not in out:
                    out.append(n)
        return out

    def read_only_at(self, geometry: Geometry, probes):
        """This space at ``geometry``, its rays read off the geometry spaces whatever
        their error estimate, or None where the grid does not hold it under every probe
        (no ray is solved; see :meth:`OnDemandRays.reading_only`).

        Parameters
        ----------
        geometry : Geometry
        probes : iterable of float

        Returns
        -------
        LoadedSpace or None
        """
        from ._geometry import _rounded_layers

        od, layers = self.on_demand, _rounded_layers(geometry, [])
        if od is None or not all(od.holds(float(p), layers) for p in probes):
            return None
        out = self.at(geometry)
        out.on_demand = od.reading_only()
        return out

    def _geometry_key(self):
        # slices read only are kept apart from those read within the tolerance
        tolerance = getattr(self.on_demand, "tolerance", None)
        return (round(self.geometry.t_d, 6), round(self.geometry.t_h, 6), tolerance)

    def _kept(self) -> dict:
        """What is kept at :attr:`geometry` (made the most recently used)."""
        geometries, key = self._shared["geometries"], self._geometry_key()
        if key in geometries:
            geometries.move_to_end(key)
        else:
            geometries[key] = {}
            while len(geometries) > GEOMETRIES_KEPT:
                geometries.popitem(last=False)
        return geometries[key]

    def probe(self, p: float):
        """The space of probe ``p`` (to 1e-6 mm) at :attr:`geometry`.

        On a grid, only its probes and layers; InputError naming them otherwise.
        On the scale-free space, any aperture of :data:`APERTURE_RANGE_MM` and any
        layers: rays the space lacks are solved on demand if :attr:`on_demand`
        allows it, else an InputError says how.

        Parameters
        ----------
        p : float
            Aperture diameter (mm).

        Returns
        -------
        ProbeSpace
            A :class:`GriddedSpace` or a :class:`NeoHookeanSlice` (shared by every
            measurement at this probe and geometry).
        """
        if self.rays is None:
            for q, s in self.spaces.items():
                if math.isclose(float(p), float(q), abs_tol=1e-6):
                    if not self.geometry.is_default:
                        raise InputError(
                            f"{self.info['path']}: a grid space has only the paper's 1 mm "
                            f"layers, not t_d = {self.geometry.t_d:g}, t_h = "
                            f"{self.geometry.t_h:g} mm (use the scale-free space)")
                    return s
            have = ", ".join(f"{q:g}" for q in self.spaces)
            raise InputError(f"{self.info['path']}: the simulated space has no {float(p):g} mm "
                             f"probe (probes: {have} mm)")
        lo, hi = APERTURE_RANGE_MM
        if not lo <= float(p) <= hi:
            raise InputError(f"probe diameter {float(p):g} mm is outside the apertures the model "
                             f"is meant for ({lo:g}-{hi:g} mm; Cutometer probes are 2, 4, 6, 8 mm)")
        reach = self.reads_up_to_mm.get(float(p))
        key = (float(p),)
        if not self.geometry.is_default and reach is not None:
            key += (round(reach, 4),)  # another reach may solve other rays
        kept = self._kept()
        if key not in kept:
            try:
                spaces, notes = spaces_at({BASELINE: self.rays}, [float(p)], self.geometry,
                                          self.on_demand, reads_up_to_mm={float(p): reach}
                                          if reach is not None else None)
            except GeometryOutsideSpace as err:
                raise InputError(f"{self.info['path']}: {err} (the command-line option "
                                 "--no-solve refuses it; drop it)") from None
            kept[key] = NeoHookeanSlice(spaces[BASELINE], float(p))
            kept[("notes", float(p))] = notes
        return kept[key]

    def cause_names(self) -> list:
        """The elastic causes whose ray spaces lie beside the neo-Hookean one (a
        scale-free space folder), in the registry's order; [] for a grid."""
        return [n for n in self._cause_spaces() if n != BASELINE]

    def _cause_spaces(self) -> dict:
        if self.rays is None or self.info.get("path") is None:
            return {}
        if "causes" not in self._shared:
            path = Path(self.info["path"])
            self._shared["causes"] = read_ray_spaces(path if path.is_dir() else path.parent)
        return self._shared["causes"]

    def cause_rays(self, name: str, probes) -> tuple:
        """``({probe: RaySpace}, notes)``: a cause's rays at :attr:`geometry`.

        On the paper's layers, the space's own rays.  At other layers the
        cause's effect on log M is carried over from the layers it was simulated
        for (:func:`skinsuction.space.spaces_at` without solving its rays, an
        approximation the notes state), on the neo-Hookean rays of these layers.

        Parameters
        ----------
        name : str
            A cause of :meth:`cause_names` (e.g. ``"strain_stiffening"``).
        probes : iterable of float

        Returns
        -------
        (dict, list of str)
            Empty rays when the cause is left out at this measurement (its
            thickness is given, or the probes lack it): the notes say why.

        Raises
        ------
        InputError
            When the space has no such cause.
        """
        spaces = self._cause_spaces()
        if name not in spaces or name == BASELINE:
            raise InputError(f"{self.info['path']}: no {name!r} rays beside the neo-Hookean "
                             f"space (causes: {', '.join(self.cause_names()) or 'none'})")
        probes = [float(p) for p in probes]
        key, kept = ("cause", name, tuple(probes)), self._kept()
        if key not in kept:
            try:
                out, notes = spaces_at({BASELINE: self.rays, name: spaces[name]}, probes,
                                       self.geometry, self.on_demand, solve_causes=False)
            except GeometryOutsideSpace as err:
                raise InputError(f"{self.info['path']}: {err}") from None
            # left out (a given thickness, or probes it was not simulated for): the
            # notes say why
            kept[key] = ({p: out[name] for p in probes} if name in out else {}, notes)
        return kept[key]

    def check_probes(self, probes) -> list:
        """The probes as floats, each checked against the space (:meth:`probe`).

        Parameters
        ----------
        probes : iterable of float

        Returns
        -------
        list of float
        """
        needed = [float(p) for p in probes]
        for p in needed:
            self.probe(p)
        return needed

    def pressure_range(self, probes) -> tuple:
        """Pressures (mbar) a curve at these probes may span.

        Parameters
        ----------
        probes : iterable of float

        Returns
        -------
        (float, float)
            The range common to the probes (the file's own, for a grid).
        """
        if self._p_range is not None:
            return self._p_range
        ranges = [self.probe(p).pressure_range for p in probes]
        return max(r[0] for r in ranges), min(r[1] for r in ranges)

    def range_note(self, probes) -> str:
        """What sets :meth:`pressure_range`, for the loader's error.

        Parameters
        ----------
        probes : iterable of float

        Returns
        -------
        str
        """
        notes = [self.probe(p).range_note() for p in probes]
        return next((n for n in notes if "scale-free" in n), notes[0])


def load_space(space_path=None, bottom: str = "fixed", *, solve_on_demand: bool | str = True,
               cache_dir=None, workers: int = 1) -> LoadedSpace:
    """Read a simulated space once, whatever its layout.

    Parameters
    ----------
    space_path : path-like, optional
        The scale-free space (its folder or its ``neo_hookean.parquet``) or a
        grid database (e.g. the paper's ``results/simulated_space/paper.parquet``).
        Default: the workflow's build in ``results/simulated_space/scale_free``
        of the working directory if there is one, else the default space
        shipped with skinsuction (:func:`skinsuction.space.resolve_space`).
        ``info`` says which (``source``, ``description``).
    bottom : str
        Bottom condition of the curves to use.
    solve_on_demand : bool or "always"
        On the scale-free space, give a measurement the rays of an aperture or of
        layer thicknesses the space lacks (:class:`skinsuction.space.OnDemandRays`):
        read off the geometry space next to it (``<space>/geometry/``, else the
        default one) where it holds them within its tolerance, else solved (16 FE
        rays a probe, cached in ``cache_dir``).  "always": solve every one, the
        geometry space unread (the reference).  False refuses them.
    cache_dir : path-like, optional
        Where rays solved on demand are kept (default
        :func:`skinsuction.space.default_cache_dir`).
    workers : int
        Processes for those solves.

    Returns
    -------
    LoadedSpace
        ``info`` says which space was read (``source``, ``description``, path,
        SHA-256).

    Raises
    ------
    skinsuction.errors.InputError
        Naming the path when it is missing, unreadable, of another bottom
        condition or not a usable grid.

    Examples
    --------
    A grid space filled by the analytic surrogate (no FE), read back:

    >>> import pathlib, tempfile
    >>> from skinsuction.identify import write_surrogate_space
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "tiny.parquet"
    >>> write_surrogate_space(path, [0.01, 0.02, 0.03, 0.04], [1e-4, 2e-4, 3e-4, 4e-4],
    ...                       [0.0, 50.0, 100.0])
    >>> space = load_space(path)
    >>> sorted(space.spaces), space.probe(6).layout, space.pressure_range([2, 6])
    ([2.0, 6.0], 'grid', (0.0, 100.0))
    >>> s6 = space.probe(6)
    >>> m = s6.interpolant_at([100.0])(s6.from_moduli([[0.02, 2e-4]]))
    >>> m.shape
    (1, 1)
    >>> load_space(path.with_name("missing.parquet"))  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    skinsuction.errors.InputError: ...missing.parquet: simulated space not found ...
    """
    src = resolve_space(space_path)
    spaces, space_meta, p_range, rays = _read_space(src.path, bottom)
    sp = src.path
    sha_of = sp if sp.is_file() else sp / "neo_hookean.parquet"
    info = {"path": str(sp), "sha256": file_sha256(sha_of),
            "name": space_meta.get("space"),
            "git_commit": (space_meta.get("git") or {}).get("commit"),
            "mesh": space_meta.get("mesh") or (space_meta.get("ray_spec") or {}).get("mesh"),
            **src.info()}
    on_demand = None
    if rays is not None and solve_on_demand:
        on_demand = OnDemandRays(rays.spec, cache_dir=cache_dir, workers=workers,
                                 geometry=geometry_file_for(sp, solve_on_demand))
    return LoadedSpace(spaces, info, p_range, bottom, rays, None, on_demand)
