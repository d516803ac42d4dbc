"""Ray spaces: extended simulated spaces stored as FE rays, thanks to the scaling law.

The model obeys ``M(s X1d, s X1h, s X2d, s X2h, s p; t_d, t_h, lambda0) =
M(X1d, X1h, X2d, X2h, p; t_d, t_h, lambda0)`` (tested in tests/test_model.py).
With ``r = X1h / X1d`` and the cause's dimensionless coordinate ``c``
(``X2d / X1d``, ``t_d`` or ``lambda0``, see :mod:`._causes`),

    M(X1d, r, c, p) = R(r, c, p * X1d_ref / X1d),

where ``R(r, c, .)`` is *one* FE curve (a ray) run at ``X1d = X1d_ref``.  So a
space over (X1d, X1h, c) needs FE runs on the 2-D grid (r, c) only, and the
neo-Hookean space a 1-D set of rays over r.  The rays are run at the smallest
X1d of the search range (``X1d_ref = X1d_min``) up to the largest measured
pressure, so a candidate X1d >= X1d_ref reads its ray at pressures
``p X1d_ref / X1d <= p``: the ray is an ordinary FE curve.  Where the FE run
stopped early (large deflections at small X1d and soft hypodermis) the ray is
NaN beyond, and candidates that need that part get cost +inf.

Interpolation (:class:`RayInterpolant`):

* across rays, cubic Lagrange in ``log10 r`` and in ``c`` (the
  :class:`skinsuction.identify.LagrangeAxis` of the identification), applied to
  ``log M`` (the deflection varies by decades over r; its logarithm is close
  to a smooth sigmoid in log r, several times more accurately interpolated than
  M itself), at the ray pressures;
* then along the pressure of the ray, cubic Lagrange on M at ``p X1d_ref / X1d``.

Each candidate first combines its 4 x 4 stencil of rays on the whole ray
pressure axis, then reads the combined ray at its own pressures, so the cost of
a call is ``N (16 n_p + 4 u)``.

Storage: one Parquet file per cause (``results/diagnosis/spaces/<cause>.parquet``)
with one row per (probe, r, c, pressure) and the cause, the axes and the
provenance in the schema metadata; the neo-Hookean space ``neo_hookean.parquet``
holds the rays at the neutral coordinate of every cause (the same FE runs).
"""

from __future__ import annotations

import logging
import math
import re
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from skinsuction.identify import LagrangeAxis
from skinsuction.space import (
    AXES,
    POINT_ID_PATTERN,
    _fmt,
    _read_parquet,
    _write_parquet,
    curve_frame,
    parse_point_id,
    point_id,
    round_sig,
)

from ._causes import BASELINE, Cause

log = logging.getLogger(__name__)

__all__ = [
    "RaySpec",
    "RaySpace",
    "RayInterpolant",
    "ray_id",
    "parse_ray_id",
    "RAY_ID_PATTERN",
    "rays_of",
    "compute_ray",
    "assemble_ray_space",
    "read_ray_space",
    "read_ray_spaces",
    "build_ray_spaces",
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
    """Where and how the rays of the diagnosis are run.

    Attributes
    ----------
    probes_mm : tuple of float
    x1d_range : (float, float)
        Search range of X1d (MPa); rays run at ``x1d_range[0]``.
    ratio_nodes : tuple of float
        Nodes of r = X1h / X1d (ascending, > 0), interpolated in log10 r.
    pressures_mbar : tuple of float
        Pressures of every ray (mbar, from 0).
    bottom : str
    mesh : dict
        Mesh settings passed to the model.
    """

    probes_mm: tuple
    x1d_range: tuple
    ratio_nodes: tuple
    pressures_mbar: tuple
    bottom: str = "fixed"
    mesh: dict = field(default_factory=dict)

    def __post_init__(self):
        set_ = object.__setattr__
        set_(self, "probes_mm", tuple(float(p) for p in self.probes_mm))
        lo, hi = (float(x) for x in self.x1d_range)
        if not 0 < lo < hi:
            raise ValueError(f"x1d range must be 0 < min < max, got {lo}, {hi}")
        set_(self, "x1d_range", (lo, hi))
        r = tuple(sorted(float(x) for x in self.ratio_nodes))
        if len(r) < 2 or r[0] <= 0 or len(set(r)) != len(r):
            raise ValueError(f"ratio nodes must be >= 2 distinct positive values, got {r}")
        set_(self, "ratio_nodes", r)
        p = tuple(float(x) for x in self.pressures_mbar)
        if p[0] != 0 or np.any(np.diff(p) <= 0):
            raise ValueError("ray pressures must start at 0 and increase")
        set_(self, "pressures_mbar", p)
        set_(self, "mesh", dict(self.mesh or {}))

    @property
    def x1d_ref(self) -> float:
        return self.x1d_range[0]

    @classmethod
    def from_config(cls, diag: dict, study_mesh: dict | None = None) -> "RaySpec":
        """From the ``diagnosis`` section (axis forms allowed); mesh = study mesh updated
        by ``diagnosis.mesh``."""
        from skinsuction.space import expand_axis

        mesh = {**(study_mesh or {}), **(diag.get("mesh") or {})}
        return cls(
            probes_mm=expand_axis(diag.get("probes_mm", [2, 6])),
            x1d_range=(diag["x1d_mpa"]["min"], diag["x1d_mpa"]["max"]),
            ratio_nodes=expand_axis(diag["ratio"]),
            pressures_mbar=expand_axis(diag["pressures_mbar"]),
            bottom=diag.get("bottom", "fixed"),
            mesh=mesh,
        )

    def to_dict(self) -> dict:
        return {"probes_mm": list(self.probes_mm), "x1d_range": list(self.x1d_range),
                "ratio_nodes": list(self.ratio_nodes),
                "pressures_mbar": list(self.pressures_mbar), "bottom": self.bottom,
                "mesh": dict(self.mesh)}


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


# ---------------------------------------------------------------------- FE rays
def compute_ray(rid: str, path, pressures_mbar, mesh: dict | None = None, metadata=None):
    """Run the FE model for the ray ``rid`` and write its curve file (atomic Parquet).

    The adapter of the workflow's ``simulate_ray`` rule.  Like
    :func:`skinsuction.space.compute_point`: a stopped solve is written as it is,
    an exception of the model is logged and written as a failed ray.
    """
    from skinsuction.model import Curve, simulate
    from skinsuction.provenance import collect

    params = parse_ray_id(rid)
    pressures = np.asarray(pressures_mbar, dtype=float)
    extras = {k: params[k] for k in EXTRA_KEYWORDS if params[k] != EXTRA_KEYWORDS[k]}
    axes = {k: params[k] for k in AXES}
    log.info("ray %s: %s %s, %d pressures, mesh %s", rid, axes, extras, pressures.size, mesh)
    start = time.perf_counter()
    try:
        curve = simulate(**axes, **extras, pressures_mbar=pressures, mesh=dict(mesh or {}))
    except TypeError as err:
        if extras and "unexpected keyword" in str(err):
            raise RuntimeError(f"ray {rid}: the model has no option {sorted(extras)} "
                               f"({err}); update skinsuction.model") from err
        raise
    except Exception as err:  # the model promises not to raise; record it if it does
        log.exception("the model raised at ray %s", rid)
        curve = Curve(pressure_mbar=pressures, deflection_mm=np.full(pressures.shape, np.nan),
                      converged=False, last_converged_mbar=float("nan"),
                      reason=f"exception: {type(err).__name__}: {err}",
                      seconds=time.perf_counter() - start)
    log.info("ray %s: converged=%s last=%s mbar reason=%r newton=%s %.1f s", rid,
             curve.converged, curve.last_converged_mbar, curve.reason,
             curve.newton_iterations, curve.seconds)
    frame = curve_frame(curve, axes)
    for k in EXTRA_KEYWORDS:
        frame[k] = float(params[k])
    frame = frame.rename(columns={"point_id": "ray_id"})
    frame["ray_id"] = rid
    meta = {"ray_id": rid, "params": params, "curve_info": dict(curve.info or {}),
            "mesh": mesh, "provenance": collect(), **(metadata or {})}
    _write_parquet(frame, path, meta)
    return curve


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


def assemble_ray_space(ray_paths, out_path, spec: RaySpec, cause: Cause | None,
                       config: dict | None = None) -> RaySpace:
    """Assemble the ray files of one model into its space file (atomic Parquet).

    Every ray of :func:`rays_of` must be among ``ray_paths`` (extra files are
    ignored); rays that stopped early keep their NaN tail.
    """
    from skinsuction.provenance import collect

    by_id = {}
    solver = {}
    for path in ray_paths:
        frame, meta = _read_parquet(path)
        rid = meta.get("ray_id") or frame["ray_id"].iloc[0]
        by_id[rid] = frame
        solver[rid] = {"converged": bool(frame["converged"].iloc[0]),
                       "last_converged_mbar": float(frame["last_converged_mbar"].iloc[0]),
                       "reason": str(frame["reason"].iloc[0]),
                       "newton_iterations": int(frame["newton_iterations"].iloc[0]),
                       "seconds": float(frame["seconds"].iloc[0])}
    p = np.asarray(spec.pressures_mbar)
    rays = rays_of(spec, cause)
    coords = np.array(cause.nodes if cause is not None else [math.nan])
    arrays = {probe: np.full((len(spec.ratio_nodes), coords.size, p.size), np.nan)
              for probe in spec.probes_mm}
    for ray in rays:
        frame = by_id.get(ray["ray_id"])
        if frame is None:
            raise ValueError(f"ray {ray['ray_id']} of the {cause.name if cause else BASELINE} "
                             "space is missing from the inputs")
        fp = frame["pressure_mbar"].to_numpy(float)
        if fp.shape != p.shape or not np.allclose(fp, p):
            raise ValueError(f"ray {ray['ray_id']}: pressures differ from the specification")
        i = spec.ratio_nodes.index(ray["ratio"])
        j = 0 if cause is None else cause.nodes.index(ray["coordinate"])
        arrays[ray["probe_mm"]][i, j] = frame["deflection_mm"].to_numpy(float)
    n_failed = sum(1 for r in rays if not solver[r["ray_id"]]["converged"])
    meta = collect(config=config, space=cause.name if cause else BASELINE,
                   cause=cause.to_dict() if cause else None, ray_spec=spec.to_dict(),
                   n_rays=len(rays), n_stopped=n_failed,
                   rays={r["ray_id"]: solver[r["ray_id"]] for r in rays})
    space = RaySpace(cause, spec, coords, arrays, meta)
    _write_parquet(space.frame(), out_path, meta)
    log.info("%s space: %d rays (%d stopped early) -> %s", space.name, len(rays), n_failed,
             out_path)
    return space


def read_ray_space(path) -> RaySpace:
    """Read a space written by :func:`assemble_ray_space`."""
    frame, meta = _read_parquet(path)
    if "ray_spec" not in meta:
        raise ValueError(f"{path}: not a ray space of the diagnosis")
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
    """All ray spaces of a directory: ``{name: RaySpace}``; the neo-Hookean one is needed.

    Raises :class:`SpaceMissingError` with the command that builds them if the
    directory or the neo-Hookean space is missing.
    """
    d = Path(space_dir)
    hint = ("build them with the workflow: `snakemake --cores 2 diagnosis_spaces` "
            "(or `--configfile config/ci.yaml` for coarse ones)")
    if not d.is_dir():
        raise SpaceMissingError(f"{d}: no such directory of diagnosis spaces; {hint}")
    spaces = {}
    for path in sorted(d.glob("*.parquet")):
        try:
            s = read_ray_space(path)
        except Exception as err:  # pyarrow raises many types for a bad file
            raise SpaceFileError(f"{path}: not a diagnosis space ({type(err).__name__}: "
                                 f"{' '.join(str(err).split())[:200]})") from None
        spaces[s.name] = s
    if BASELINE not in spaces:
        raise SpaceMissingError(f"{d}: no {BASELINE}.parquet (the neo-Hookean rays); {hint}")
    return spaces


def build_ray_spaces(spec: RaySpec, causes: dict, out_dir=None, workers: int = 1,
                     config=None) -> dict:
    """Run every ray in this process (or a pool) and return ``{name: RaySpace}``.

    For tests, notebooks and benchmarks; the workflow runs one job per ray.
    With ``out_dir`` the ray and space files are written there
    (``out_dir/rays/<id>.parquet``, ``out_dir/<name>.parquet``); files of rays
    already present are reused.
    """
    import tempfile

    tmp = None
    if out_dir is None:
        tmp = tempfile.TemporaryDirectory(prefix="skinsuction-rays-")
        out_dir = tmp.name
    out = Path(out_dir)
    (out / "rays").mkdir(parents=True, exist_ok=True)
    models = {BASELINE: None, **causes}
    todo = {}
    for cause in models.values():
        for ray in rays_of(spec, cause):
            path = out / "rays" / f"{ray['ray_id']}.parquet"
            if not path.exists():
                todo[ray["ray_id"]] = path
    jobs = [(rid, str(path), spec.pressures_mbar, spec.mesh) for rid, path in todo.items()]
    if workers > 1 and len(jobs) > 1:
        from concurrent.futures import ProcessPoolExecutor

        with ProcessPoolExecutor(workers) as pool:
            list(pool.map(_compute_ray_job, jobs))
    else:
        for job in jobs:
            _compute_ray_job(job)
    spaces = {}
    for name, cause in models.items():
        paths = [out / "rays" / f"{r['ray_id']}.parquet" for r in rays_of(spec, cause)]
        spaces[name] = assemble_ray_space(paths, out / f"{name}.parquet", spec, cause, config)
    if tmp is not None:
        tmp.cleanup()
    return spaces


def _compute_ray_job(job):
    rid, path, pressures, mesh = job
    compute_ray(rid, path, pressures, mesh)
    return rid


# ------------------------------------------------------------------ interpolation
def _weights_at(axis: LagrangeAxis, x, start) -> np.ndarray:
    """Lagrange weights of the stencils starting at ``start`` (not necessarily centred)."""
    from skinsuction.identify._interpolate import _numerators

    m = axis.m
    table = axis._table[start]
    w = _numerators(np.asarray(x, dtype=float)[:, None] - table[:, :m])
    w /= table[:, m:]
    return w


def _alternative_starts(axis: LagrangeAxis, x, centred):
    """Other stencil starts that still contain the cell of each x: [None, shifts...].

    ``None`` stands for the centred start; a shift that leaves the cell outside the
    stencil falls back to the centred one for that point.
    """
    cell = np.clip(np.searchsorted(axis.nodes, x, side="right") - 1, 0, axis.nodes.size - 2)
    lo = np.maximum(cell + 2 - axis.m, 0)
    hi = np.minimum(cell, axis.n_starts - 1)
    out = [None]
    for shift in (1, -1, 2, -2):
        s = centred + shift
        ok = (s >= lo) & (s <= hi)
        if ok.any():
            out.append(np.where(ok, s, centred))
    return out


class RayInterpolant:
    """M(X1d, X1h, c, p) of one probe at fixed measured pressures, vectorised.

    Parameters
    ----------
    space : RaySpace
    probe_mm : float
    pressure_mbar : array_like (u,)
        Measured pressures (mbar), within the ray pressures.

    Calling it with ``theta (N, d)`` = ``(log10 X1d, log10 r[, c])`` returns the
    deflections (N, u) in mm; NaN outside the space or where a ray stopped.
    """

    def __init__(self, space: RaySpace, probe_mm: float, pressure_mbar):
        self.space = space
        self.probe_mm = float(probe_mm)
        p = np.asarray(pressure_mbar, dtype=float).reshape(-1)
        pr = np.asarray(space.spec.pressures_mbar)
        if np.any(p < 0) or np.any(p > pr[-1] + 1e-9):
            raise ValueError(f"pressures must lie in 0..{pr[-1]:g} mbar (the rays' range)")
        self.pressure_mbar = p
        self.x1d_ref = space.spec.x1d_ref
        rays = space.rays(probe_mm)  # (n_r, n_c, n_p)
        with np.errstate(divide="ignore", invalid="ignore"):
            g = np.log(rays[..., 1:])  # log M at p > 0; M(0) = 0
        g[~np.isfinite(g)] = np.nan  # a zero or negative deflection is unusable
        self._g = g
        self._axis_r = LagrangeAxis(np.log10(space.spec.ratio_nodes))
        self._axis_c = LagrangeAxis(space.coordinates) if space.cause is not None else None
        self._axis_p = LagrangeAxis(pr)
        self.d = 2 if space.cause is None else 3

    @property
    def lower(self) -> np.ndarray:
        s = self.space.spec
        lo = [math.log10(s.x1d_range[0]), math.log10(s.ratio_nodes[0])]
        if self.d == 3:
            lo.append(self.space.cause.lower)
        return np.array(lo)

    @property
    def upper(self) -> np.ndarray:
        s = self.space.spec
        hi = [math.log10(s.x1d_range[1]), math.log10(s.ratio_nodes[-1])]
        if self.d == 3:
            hi.append(self.space.cause.upper)
        return np.array(hi)

    def _combine(self, theta, start_r, start_c=None):
        """log M of the candidates' rays with the given stencil starts, (N, n_p - 1)."""
        wr = _weights_at(self._axis_r, theta[:, 1], start_r)
        ir = start_r[:, None] + np.arange(self._axis_r.m)
        # a ray with weight exactly 0 (the candidate sits on a node) is ignored, so a
        # neighbouring ray that stopped early does not spoil a node (NaN * 0 = NaN)
        if self.d == 2:
            stencil = self._g[ir, 0]  # (N, mr, n_p - 1)
            stencil = np.where((wr == 0.0)[:, :, None], 0.0, stencil)
            return np.einsum("nk,nkp->np", wr, stencil)
        wc = _weights_at(self._axis_c, theta[:, 2], start_c)
        ic = start_c[:, None] + np.arange(self._axis_c.m)
        stencil = self._g[ir[:, :, None], ic[:, None, :]]  # (N, mr, mc, n_p - 1)
        w = wr[:, :, None] * wc[:, None, :]
        stencil = np.where((w == 0.0)[..., None], 0.0, stencil)
        return np.einsum("nkl,nklp->np", w, stencil)

    def combined_rays(self, theta) -> np.ndarray:
        """The rays at (r, c) of the candidates on the ray pressures, (N, n_p), mm.

        NaN policy "shift" (as the identification's): where the centred stencil
        holds a ray that stopped early, the other stencils that still contain the
        candidate's cell are tried in turn, pressure by pressure.
        """
        theta = np.asarray(theta, dtype=float)
        n = theta.shape[0]
        sr, wr = self._axis_r.weights(theta[:, 1])
        outside = np.isnan(wr[:, 0])
        sc = None
        if self.d == 3:
            sc, wc = self._axis_c.weights(theta[:, 2])
            outside |= np.isnan(wc[:, 0])
        g = self._combine(theta, sr, sc)
        g[outside] = np.nan  # no extrapolation
        bad = np.flatnonzero(np.isnan(g).any(axis=1) & ~outside)
        if bad.size:
            th = theta[bad]
            opt_r = _alternative_starts(self._axis_r, th[:, 1], sr[bad])
            opt_c = (_alternative_starts(self._axis_c, th[:, 2], sc[bad]) if self.d == 3
                     else [None])
            sub = g[bad]
            for a in opt_r:
                for b in opt_c:
                    if a is None and b is None:
                        continue
                    ra = sr[bad] if a is None else a
                    cb = None if self.d == 2 else (sc[bad] if b is None else b)
                    hole = np.isnan(sub)
                    if not hole.any():
                        break
                    alt = self._combine(th, ra, cb)
                    sub = np.where(hole, alt, sub)
            g[bad] = sub
        out = np.empty((n, g.shape[1] + 1))
        out[:, 0] = 0.0
        np.exp(g, out=out[:, 1:])
        return out

    def __call__(self, theta) -> np.ndarray:
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        if theta.shape[1] != self.d:
            raise ValueError(f"candidates must have {self.d} columns, got {theta.shape}")
        n, u = theta.shape[0], self.pressure_mbar.size
        rays = self.combined_rays(theta)  # (N, n_p)
        x1d = 10.0 ** theta[:, 0]
        q = self.pressure_mbar[None, :] * (self.x1d_ref / x1d)[:, None]  # (N, u)
        start, w = self._axis_p.weights(q.reshape(-1))
        idx = start[:, None] + np.arange(self._axis_p.m)  # (N u, m)
        rows = np.repeat(np.arange(n), u)[:, None]
        nodes = rays[rows, idx]
        vals = np.where(w == 0.0, 0.0, w * nodes).sum(axis=1)
        # below X1d_ref the ray would be read beyond its range: outside the space
        vals[np.repeat(x1d < self.x1d_ref * (1 - 1e-12), u)] = np.nan
        return vals.reshape(n, u)
