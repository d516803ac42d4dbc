"""The rays of the scale-free space stored and read back: one file per model.

The FE jobs write bundles of rays (one per model, probe and run of X1h/X1d,
:func:`skinsuction.space.ray_bundles`); :func:`assemble_ray_space` writes one
Parquet file per model (``results/simulated_space/scale_free/<model>.parquet``)
with one row per (probe, r, c, pressure) and the cause, the axes, the coverage
and the provenance in the schema metadata; ``neo_hookean.parquet`` holds the
rays at the neutral coordinate of every cause (the same FE runs).
:func:`read_ray_space` gives back a :class:`RaySpace`, the rays of one model
as arrays (probe -> (ratio, coordinate, pressure)).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from ._causes import BASELINE, Cause
from ._rays import RaySpec, rays_of
from ._storage import _read_parquet, _write_parquet

log = logging.getLogger(__name__)

__all__ = ["RaySpace", "coverage_frontier", "assemble_ray_space", "read_ray_space",
           "read_ray_spaces", "SpaceMissingError", "SpaceFileError"]


class SpaceMissingError(FileNotFoundError):
    """The ray spaces the diagnosis needs are not there (build them with the workflow)."""


class SpaceFileError(ValueError):
    """A file of the space directory is not a ray space of the diagnosis."""


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
        """``neo_hookean`` or the cause's name."""
        return BASELINE if self.cause is None else self.cause.name

    @property
    def probes_mm(self) -> tuple:
        """The apertures (mm) the space has rays of, ascending."""
        return tuple(sorted(self.deflection_mm))

    def has_probe(self, probe_mm: float) -> bool:
        """Whether the space has rays of this aperture (to 1e-6 mm).

        Parameters
        ----------
        probe_mm : float

        Returns
        -------
        bool
        """
        return any(math.isclose(probe_mm, p, abs_tol=1e-6) for p in self.deflection_mm)

    def rays(self, probe_mm: float) -> np.ndarray:
        """The rays of one aperture.

        Parameters
        ----------
        probe_mm : float
            To 1e-6 mm.

        Returns
        -------
        ndarray, shape (n_r, n_c, n_p)
            Deflections (mm) by X1h/X1d node, coordinate and pressure of the FE run.

        Raises
        ------
        KeyError
            Naming the probes of the space, if it has not this one.
        """
        for p, a in self.deflection_mm.items():
            if math.isclose(probe_mm, p, abs_tol=1e-6):
                return a
        raise KeyError(f"no {probe_mm:g} mm rays in the {self.name} space "
                       f"(probes: {', '.join(f'{p:g}' for p in self.probes_mm)} mm)")

    def null_slice(self) -> "RaySpace":
        """The neo-Hookean rays of this space (its neutral coordinate).

        Returns
        -------
        RaySpace
            Itself for the neo-Hookean space.
        """
        if self.cause is None:
            return self
        j = int(np.argmin(np.abs(self.coordinates - self.cause.neutral)))
        return RaySpace(None, self.spec, np.array([math.nan]),
                        {p: a[:, j:j + 1] for p, a in self.deflection_mm.items()},
                        dict(self.metadata))

    def frame(self) -> pd.DataFrame:
        """The rays in long format, as the space file stores them.

        Returns
        -------
        pandas.DataFrame
            ``probe_mm, ratio, coordinate, pressure_mbar, deflection_mm``, one row
            per ray and pressure.
        """
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
    """The highest load p/X1d each ray reached.

    Parameters
    ----------
    space : RaySpace

    Returns
    -------
    pandas.DataFrame
        One row per (probe, ratio, coordinate): ``model, probe_mm, ratio,
        coordinate, load_reached, load_max, complete, reason, mesh_fallback,
        ray_id``.  ``complete`` is True where the ray reaches ``load_max``;
        ``reason`` is the solver's reason where it stopped.
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


def fill_rays(bundle_paths, rays: list, arrays: dict, spec: RaySpec, name: str,
              column) -> dict:
    """Put the rays of the bundle files into ``arrays[probe][ratio index, column(ray)]``.

    Parameters
    ----------
    bundle_paths : iterable of path-like
    rays : list of dict
        The rays wanted (:func:`rays_of` or a pair's), each with ``ray_id``,
        ``probe_mm`` and ``ratio``.
    arrays : dict
        ``{probe: (n_r, n_c, n_p)}``, filled in place.
    spec : RaySpec
    name : str
        The space's name, for errors.
    column : callable
        The column of a ray.

    Returns
    -------
    dict
        ``{ray_id: solver record}``.

    Raises
    ------
    ValueError
        A ray missing from the bundles, or solved at other pressures.
    """
    by_id, solver = {}, {}
    for path in bundle_paths:
        frame, meta = _read_parquet(path)
        for rid, g in frame.groupby("ray_id", sort=False):
            by_id[rid] = g
            solver[rid] = (meta.get("rays") or {}).get(rid, {})
    p = np.asarray(spec.pressures_mbar)
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
        arrays[ray["probe_mm"]][i, column(ray)] = frame["deflection_mm"].to_numpy(float)
    return {r["ray_id"]: solver[r["ray_id"]] for r in rays}


def assemble_ray_space(bundle_paths, out_path, spec: RaySpec, cause: Cause | None,
                       config: dict | None = None) -> RaySpace:
    """Assemble the bundle files of one model into its space file (atomic Parquet).

    Every ray of :func:`rays_of` must be in one of ``bundle_paths`` (extra rays
    are ignored); rays that stopped early keep their NaN tail, and the coverage
    frontier (:func:`coverage_frontier`) goes into the metadata.

    Parameters
    ----------
    bundle_paths : iterable of path-like
        Bundle files (:func:`skinsuction.space.compute_bundle`).
    out_path : path-like
        The space file, conventionally ``<space dir>/<model>.parquet``.
    spec : RaySpec
    cause : Cause or None
        The model (None: neo-Hookean).
    config : dict, optional
        The configuration, recorded in the provenance.

    Returns
    -------
    RaySpace
    """
    from skinsuction.provenance import collect

    p = np.asarray(spec.pressures_mbar)
    rays = rays_of(spec, cause)
    coords = np.array(cause.nodes if cause is not None else [math.nan])
    arrays = {probe: np.full((len(spec.ratio_nodes), coords.size, p.size), np.nan)
              for probe in spec.probes_mm}
    name = cause.name if cause else BASELINE
    ray_info = fill_rays(bundle_paths, rays, arrays, spec, name,
                         lambda ray: 0 if cause is None else cause.nodes.index(ray["coordinate"]))
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
    """Read a space written by :func:`assemble_ray_space`.

    Parameters
    ----------
    path : path-like

    Returns
    -------
    RaySpace

    Raises
    ------
    ValueError
        If the file is not a scale-free space.
    """
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
    """All spaces of a scale-free space directory.

    Parameters
    ----------
    space_dir : path-like
        The folder (or one of its model files).

    Returns
    -------
    dict
        ``{name: RaySpace}``; ``neo_hookean`` is always there.

    Raises
    ------
    SpaceMissingError
        With the command that builds them, if the directory or the neo-Hookean
        space is missing.
    SpaceFileError
        Naming a file of the folder that is not a scale-free space.
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
