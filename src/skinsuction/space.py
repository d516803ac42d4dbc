"""The simulated space Omega_s: grids of FE suction curves stored as Parquet.

The paper (section 2.3, eq. 2-3) precomputes the apex deflection M(x, p, v) on a
grid of material parameters x = (X1d, X1h) and pressures p, for a given aperture
(probe diameter). This module

* expands the grid specifications of the configuration (:func:`expand_axis`,
  :func:`grid_points`),
* names every grid point by a readable, unique id (:func:`point_id`,
  :func:`parse_point_id`),
* writes one FE curve per point (:func:`write_curve`) and assembles the curves of a
  space into one long-format database with provenance (:func:`assemble_space`),
* reads a database back as a :class:`SimulatedSpace` whose :meth:`SimulatedSpace.grid`
  gives the dense array used by the identification.

A grid axis is specified as a number, a list of values, a range
``{start, stop, step}`` (both ends included) or ``{logspace: [a, b, n]}``
(``n`` values from ``10**a`` to ``10**b``). Values are rounded to 12 significant
digits so that ranges are free of floating-point round-off.

Examples
--------
>>> expand_axis({"start": 0.001, "stop": 0.091, "step": 0.009})[-1]
0.091
>>> pts = grid_points({"probes_mm": [6], "x1d": [0.08], "x1h": [0.00041]})
>>> point_id(pts[0])
'p6_fixed_x1d0.08_x1h0.00041_x2d0_x2h0_td1_th1'
>>> parse_point_id(point_id(pts[0])) == pts[0]
True
"""

from __future__ import annotations

import contextlib
import itertools
import json
import logging
import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

log = logging.getLogger(__name__)

#: Parameters of one grid point, in the order used by point ids and sorting.
AXES = ("probe_mm", "bottom", "x1d", "x1h", "x2d", "x2h", "t_d", "t_h")

#: Keys of a space specification (config) and the grid axis each one fills.
SPEC_KEYS = {
    "probes_mm": "probe_mm",
    "bottom": "bottom",
    "x1d": "x1d",
    "x1h": "x1h",
    "x2d": "x2d",
    "x2h": "x2h",
    "t_d": "t_d",
    "t_h": "t_h",
}

#: Axis values used when a space specification omits the axis.
DEFAULTS = {
    "bottom": ["fixed"],
    "x2d": [0.0],
    "x2h": [0.0],
    "t_d": [1.0],
    "t_h": [1.0],
}

#: Boundary conditions at the hypodermis/bone interface (paper section 3.1).
BOTTOMS = ("fixed", "axial", "free")

#: Columns of a curve file and of a simulated-space database, in order.
COLUMNS = (
    *AXES,
    "pressure_mbar",
    "deflection_mm",
    "converged",
    "last_converged_mbar",
    "reason",
    "newton_iterations",
    "dofs",
    "seconds",
    "mesh_fallback",
    "point_id",
)

#: Key of the JSON provenance record in the Parquet schema metadata.
METADATA_KEY = b"skinsuction"

SIGNIFICANT_DIGITS = 12


# --------------------------------------------------------------------------- axes
def round_sig(value: float, digits: int = SIGNIFICANT_DIGITS) -> float:
    """``value`` rounded to ``digits`` significant digits (``-0.0`` becomes ``0.0``).

    >>> round_sig(0.001 + 10 * 0.009)
    0.091
    """
    return float(f"{float(value):.{digits}g}") + 0.0


def _is_number(x) -> bool:
    return isinstance(x, (int, float, np.integer, np.floating)) and not isinstance(
        x, (bool, np.bool_)
    )


def expand_axis(spec) -> list:
    """Values of one grid axis from its configuration.

    Parameters
    ----------
    spec : number, str, list, or dict
        A single value, a list of values (numbers or, for ``bottom``, strings),
        ``{"start": a, "stop": b, "step": h}`` (``a, a+h, ..., b``; ``b`` included
        when it lies on the grid), or ``{"logspace": [a, b, n]}`` (``n`` values
        from ``10**a`` to ``10**b``, log-uniform).

    Returns
    -------
    list
        Python floats rounded to 12 significant digits (strings unchanged), in
        the given order (ranges ascending).

    Raises
    ------
    ValueError
        For an empty list, duplicate values, a non-positive step, ``stop < start``
        or an unknown form.

    Examples
    --------
    >>> expand_axis({"start": 1.0e-5, "stop": 2.01e-3, "step": 2.0e-4})[:3]
    [1e-05, 0.00021, 0.00041]
    >>> expand_axis({"logspace": [-5, -1, 5]})
    [1e-05, 0.0001, 0.001, 0.01, 0.1]
    >>> expand_axis(0.08)
    [0.08]
    >>> expand_axis(["fixed", "axial"])
    ['fixed', 'axial']
    """
    if isinstance(spec, str):
        values = [spec]
    elif _is_number(spec):
        values = [round_sig(spec)]
    elif isinstance(spec, (list, tuple)):
        if not spec:
            raise ValueError("an axis needs at least one value")
        values = [v if isinstance(v, str) else _checked_number(v) for v in spec]
    elif isinstance(spec, dict) and set(spec) == {"start", "stop", "step"}:
        start, stop, step = (_checked_number(spec[k]) for k in ("start", "stop", "step"))
        if not step > 0:
            raise ValueError(f"step must be > 0, got {step}")
        if stop < start:
            raise ValueError(f"stop ({stop}) must be >= start ({start})")
        n = int(math.floor((stop - start) / step + 1e-9)) + 1
        values = [round_sig(start + i * step) for i in range(n)]
    elif isinstance(spec, dict) and set(spec) == {"logspace"}:
        a, b, n = spec["logspace"]
        if int(n) != n or n < 1:
            raise ValueError(f"logspace needs a whole number of values >= 1, got {n}")
        values = [round_sig(v) for v in 10.0 ** np.linspace(float(a), float(b), int(n))]
    else:
        raise ValueError(
            "an axis is a value, a list, {start, stop, step} or {logspace: [a, b, n]}; "
            f"got {spec!r}"
        )
    if len(set(values)) != len(values):
        raise ValueError(f"duplicate values on an axis: {values}")
    return values


def _checked_number(v) -> float:
    if not _is_number(v) or not math.isfinite(v):
        raise ValueError(f"not a finite number: {v!r}")
    return round_sig(v)


def grid_points(space_spec: dict, ignore=()) -> list[dict]:
    """All grid points of a space specification (cartesian product of its axes).

    Parameters
    ----------
    space_spec : dict
        Keys among ``probes_mm, bottom, x1d, x1h, x2d, x2h, t_d, t_h``; each value
        an axis specification (see :func:`expand_axis`). ``probes_mm``, ``x1d`` and
        ``x1h`` are required; the others default to ``bottom=fixed``, ``x2d=x2h=0``,
        ``t_d=t_h=1`` mm.
    ignore : iterable of str
        Keys of ``space_spec`` that are not axes (e.g. ``pressure_mbar`` of the
        Figure 3 specification).

    Returns
    -------
    list of dict
        One dict per point with keys :data:`AXES`, ordered by probe, bottom,
        X1d, X1h, X2d, X2h, t_d, t_h (last varies fastest).

    Examples
    --------
    >>> spec = {"probes_mm": [2, 6], "x1d": {"start": 0.001, "stop": 0.091, "step": 0.009},
    ...         "x1h": {"start": 1.0e-5, "stop": 2.01e-3, "step": 2.0e-4}}
    >>> len(grid_points(spec))
    242
    """
    unknown = set(space_spec) - set(SPEC_KEYS) - set(ignore)
    if unknown:
        raise ValueError(f"unknown keys in a space specification: {sorted(unknown)}")
    missing = {"probes_mm", "x1d", "x1h"} - set(space_spec)
    if missing:
        raise ValueError(f"a space specification needs {sorted(missing)}")
    axes = {}
    for key, axis in SPEC_KEYS.items():
        spec = space_spec.get(key, DEFAULTS.get(axis))
        axes[axis] = expand_axis(spec)
    bad = set(axes["bottom"]) - set(BOTTOMS)
    if bad:
        raise ValueError(f"bottom must be among {BOTTOMS}, got {sorted(bad)}")
    return [dict(zip(AXES, combo)) for combo in itertools.product(*(axes[a] for a in AXES))]


# ------------------------------------------------------------------------ point ids
def _fmt(x: float) -> str:
    return "%.12g" % x


_ID = re.compile(
    r"^p(?P<probe_mm>[^_]+)_(?P<bottom>[a-z]+)"
    r"_x1d(?P<x1d>[^_]+)_x1h(?P<x1h>[^_]+)_x2d(?P<x2d>[^_]+)_x2h(?P<x2h>[^_]+)"
    r"_td(?P<t_d>[^_]+)_th(?P<t_h>[^_]+)$"
)

#: Regular expression for point ids, used as Snakemake wildcard constraint.
POINT_ID_PATTERN = r"p[^/_]+_[a-z]+_x1d[^/_]+_x1h[^/_]+_x2d[^/_]+_x2h[^/_]+_td[^/_]+_th[^/_]+"


def point_id(params: dict) -> str:
    """Readable unique name of a grid point, used in file names.

    Numbers are written with 12 significant digits (``%.12g``), so the id is
    exact for grid values (which :func:`expand_axis` rounds to 12 digits).

    Examples
    --------
    >>> point_id(dict(probe_mm=6, bottom="fixed", x1d=0.08, x1h=1e-5,
    ...               x2d=0, x2h=0, t_d=1, t_h=1))
    'p6_fixed_x1d0.08_x1h1e-05_x2d0_x2h0_td1_th1'
    """
    p = {**{k: v[0] for k, v in DEFAULTS.items()}, **params}
    if p["bottom"] not in BOTTOMS:
        raise ValueError(f"bottom must be among {BOTTOMS}, got {p['bottom']!r}")
    return (
        f"p{_fmt(p['probe_mm'])}_{p['bottom']}"
        f"_x1d{_fmt(p['x1d'])}_x1h{_fmt(p['x1h'])}"
        f"_x2d{_fmt(p['x2d'])}_x2h{_fmt(p['x2h'])}"
        f"_td{_fmt(p['t_d'])}_th{_fmt(p['t_h'])}"
    )


def parse_point_id(pid: str) -> dict:
    """The grid point parameters encoded in a point id (inverse of :func:`point_id`).

    >>> parse_point_id("p2_free_x1d0.08_x1h0.1_x2d0_x2h0_td1_th1.5")["t_h"]
    1.5
    """
    m = _ID.match(pid)
    if m is None:
        raise ValueError(f"not a point id: {pid!r}")
    out = {}
    for key in AXES:
        text = m.group(key)
        if key == "bottom":
            if text not in BOTTOMS:
                raise ValueError(f"unknown bottom condition {text!r} in point id {pid!r}")
            out[key] = text
        else:
            try:
                out[key] = round_sig(float(text))
            except ValueError:
                raise ValueError(f"bad number {text!r} for {key} in point id {pid!r}") from None
    return out


# --------------------------------------------------------------------- atomic files
@contextlib.contextmanager
def atomic_output(path):
    """Yield a temporary path next to ``path``; move it to ``path`` on success.

    On an exception the temporary file is removed and ``path`` is left as it was,
    so a reader never sees a partially written file.

    Examples
    --------
    >>> import tempfile
    >>> target = Path(tempfile.mkdtemp()) / "t.txt"
    >>> with atomic_output(target) as tmp:
    ...     _ = tmp.write_text("done")
    >>> target.read_text()
    'done'
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp{path.suffix}")
    # a writer killed before its move (SIGKILL, power cut) leaves its temporary file:
    # the next writer of the same output removes it (one job writes an output)
    for stale in path.parent.glob(f".{path.name}.*.tmp{path.suffix}"):
        if stale != tmp:
            with contextlib.suppress(FileNotFoundError):
                stale.unlink()
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()


def _write_parquet(frame: pd.DataFrame, path, meta: dict) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    from skinsuction.provenance import jsonable

    table = pa.Table.from_pandas(frame, preserve_index=False)
    schema_meta = dict(table.schema.metadata or {})
    schema_meta[METADATA_KEY] = json.dumps(jsonable(meta), sort_keys=True).encode()
    table = table.replace_schema_metadata(schema_meta)
    with atomic_output(path) as tmp:
        pq.write_table(table, tmp)


def _read_parquet(path) -> tuple[pd.DataFrame, dict]:
    import pyarrow.parquet as pq

    table = pq.read_table(path)
    raw = (table.schema.metadata or {}).get(METADATA_KEY)
    meta = json.loads(raw) if raw else {}
    return table.to_pandas(), meta


# ------------------------------------------------------------------------- curves
def curve_frame(curve, params: dict) -> pd.DataFrame:
    """The long-format rows (one per pressure) of one FE curve at a grid point.

    ``curve`` is a :class:`skinsuction.model.Curve` (or any object with its
    attributes). Deflections beyond ``last_converged_mbar`` of a non-converged
    curve are set to NaN.
    """
    p = np.asarray(curve.pressure_mbar, dtype=float)
    m = np.asarray(curve.deflection_mm, dtype=float).copy()
    if p.shape != m.shape or p.ndim != 1:
        raise ValueError(
            f"pressure ({p.shape}) and deflection ({m.shape}) must be 1-D of equal length"
        )
    converged = bool(curve.converged)
    last = float(curve.last_converged_mbar) if curve.last_converged_mbar is not None else np.nan
    if not converged:
        beyond = ~(p <= last)  # NaN last -> everything beyond
        m[beyond] = np.nan
    params = {**{k: v[0] for k, v in DEFAULTS.items()}, **params}
    n = len(p)
    data = {}
    for key in AXES:
        value = params[key]
        data[key] = [value] * n if key == "bottom" else np.full(n, float(value))
    data.update(
        pressure_mbar=p,
        deflection_mm=m,
        converged=np.full(n, converged),
        last_converged_mbar=np.full(n, last),
        reason=[str(curve.reason or "")] * n,
        newton_iterations=np.full(n, int(curve.newton_iterations or 0), dtype=np.int64),
        dofs=np.full(n, int(curve.dofs or 0), dtype=np.int64),
        seconds=np.full(n, float(curve.seconds or 0.0)),
        mesh_fallback=np.full(n, bool((getattr(curve, "info", None) or {}).get("mesh_fallback"))),
        point_id=[point_id(params)] * n,
    )
    return pd.DataFrame(data, columns=list(COLUMNS))


def write_curve(curve, params: dict, path, metadata: dict | None = None) -> Path:
    """Write one FE curve at a grid point to a Parquet file (atomically).

    Parameters
    ----------
    curve : skinsuction.model.Curve
        Result of :func:`skinsuction.model.simulate`; a failed curve is written too.
    params : dict
        Grid point parameters (keys :data:`AXES`).
    path : path-like
        Output file, conventionally ``results/curves/<point_id>.parquet``.
    metadata : dict, optional
        Extra JSON-able provenance stored with ``curve.info`` in the schema metadata.
    """
    frame = curve_frame(curve, params)
    meta = {
        "point_id": frame["point_id"].iloc[0],
        "point": {k: params.get(k, DEFAULTS.get(k, [None])[0]) for k in AXES},
        "curve_info": dict(getattr(curve, "info", {}) or {}),
        **(metadata or {}),
    }
    _write_parquet(frame, path, meta)
    return Path(path)


def _reached(curve) -> float:
    return float(np.nan_to_num(curve.last_converged_mbar, nan=-1.0))


def _splice(curve, other, pressures):
    """``curve`` where it converged, ``other`` beyond, scaled to meet it there."""
    import dataclasses

    m0 = np.asarray(curve.deflection_mm, dtype=float)
    m1 = np.asarray(other.deflection_mm, dtype=float)
    ok = np.flatnonzero((pressures <= _reached(curve)) & np.isfinite(m0))
    if ok.size < 2 or not np.isfinite(m1[ok[-1]]) or m1[ok[-1]] == 0:
        return other, None
    k = ok[-1]
    factor = float(m0[k] / m1[k])
    merged = m1 * factor
    merged[: k + 1] = m0[: k + 1]
    info = {**(other.info or {}), "spliced_at_mbar": float(pressures[k]),
            "splice_factor": factor}
    return dataclasses.replace(other, deflection_mm=merged, info=info), float(pressures[k])


def solve_with_fallbacks(params: dict, pressures_mbar, mesh: dict | None = None, fallback=None,
                         label: str = "model", splice: bool = False):
    """Solve the FE model, then the fallback meshes in order while it stops early.

    The chain of :func:`compute_point`, for any model keywords (``params`` are
    passed to :func:`skinsuction.model.simulate`, e.g. with ``prestretch``).
    An exception of the model is logged and returned as a failed curve (all
    NaN, ``reason="exception: ..."``), never raised, except
    :class:`skinsuction.model.ParameterError` (parameters or mesh settings the
    model refuses), which is raised: a workflow job fails loudly.

    ``splice=True`` keeps the first solve's curve up to where it converged and
    takes only the rest from the fallback, scaled to meet it there (``info``
    records ``spliced_at_mbar`` and ``splice_factor``): a fallback element locks
    slightly (up to 0.9 % for stiff skin), and a curve that switched element
    over its whole range would differ by that from a run of the same skin at a
    lower load that the default converges.  The scale-free space and its checks
    splice; the paper grid keeps whole fallback curves.

    Returns
    -------
    (Curve, int, str or None)
        The curve that reaches the highest pressure (its ``seconds`` count every
        solve, its ``info["mesh_fallback"]`` says which fallback, from 1), the
        index of that fallback (0: the first solve) and the first solve's reason
        when a fallback's curve was kept.
    """
    import dataclasses
    import time

    from skinsuction import model
    from skinsuction.model import Curve, simulate

    # a stand-in model (workflow tests) may not define it: then nothing is refused
    ParameterError = getattr(model, "ParameterError", ())  # noqa: N806

    pressures = np.asarray(pressures_mbar, dtype=float)

    def solve(settings, budget=None):
        log.info("%s: %s, %d pressures, mesh %s", label, params, pressures.size, settings)
        start = time.perf_counter()
        try:
            extra = {} if budget is None else {"iteration_budget": budget}
            curve = simulate(**params, pressures_mbar=pressures, mesh=settings, **extra)
        except ParameterError as err:
            # refused parameters or mesh settings are the configuration's error, not a
            # non-converged point: the job fails, loudly, naming them
            raise ParameterError(f"{label}: the model refuses {params} with mesh "
                                 f"{settings}: {err}") from None
        except Exception as err:  # the model promises not to raise; record it if it does
            log.exception("the model raised at %s", label)
            curve = Curve(
                pressure_mbar=pressures,
                deflection_mm=np.full(pressures.shape, np.nan),
                converged=False,
                last_converged_mbar=float("nan"),
                reason=f"exception: {type(err).__name__}: {err}",
                seconds=time.perf_counter() - start,
            )
        log.info("%s: converged=%s last=%s mbar reason=%r newton=%s dofs=%s %.1f s", label,
                 curve.converged, curve.last_converged_mbar, curve.reason,
                 curve.newton_iterations, curve.dofs, curve.seconds)
        return curve

    curve = solve(dict(mesh or {}))
    first_reason, kept, spent = None, 0, curve.seconds
    fallbacks = [fallback] if isinstance(fallback, dict) else list(fallback or [])
    for k, settings in enumerate(fallbacks, start=1):
        if curve.converged:
            break
        settings = dict(settings)
        per_step = settings.pop("iterations_per_step", 20)
        other = solve({**dict(mesh or {}), **settings}, per_step * pressures.size)
        spent += other.seconds
        if _reached(other) > _reached(curve):
            log.info("%s: kept the curve of fallback %d", label, k)
            first_reason = curve.reason if kept == 0 else first_reason
            if splice:
                other, at = _splice(curve, other, pressures)
                if at is not None:
                    log.info("%s: spliced at %g mbar (factor %.6f)", label, at,
                             other.info["splice_factor"])
            kept, curve = k, other
    if kept:
        curve = dataclasses.replace(curve, info={**(curve.info or {}), "mesh_fallback": kept})
    if spent != curve.seconds:  # every solve's time counts
        curve = dataclasses.replace(curve, seconds=spent)
    return curve, kept, first_reason



def compute_point(
    pid: str, path, pressures_mbar, mesh: dict | None = None, metadata=None, fallback=None
):
    """Run the FE model at the grid point ``pid`` and write its curve file.

    The adapter of the workflow's ``simulate_point`` rule. A solve that does not
    converge is written as it is (``converged=False``); an exception raised by
    the model is logged with its traceback and written as a failed point too
    (``reason="exception: ..."``, all deflections NaN), so that a space never
    silently loses a grid point.

    Parameters
    ----------
    pid : str
        Point id (see :func:`point_id`).
    path : path-like
        Output curve file.
    pressures_mbar : sequence of float
        Pressures of the curve, ascending from 0.
    mesh : dict, optional
        Mesh and solver settings (``config["mesh"]``), passed through.
    metadata : dict, optional
        Extra provenance (e.g. the source hash of the model).
    fallback : dict or list of dict, optional
        Mesh settings (``config["mesh_fallback"]``) that replace those of ``mesh``
        for another solve while the solves so far stopped early, in order, each
        with ``iterations_per_step`` (its Newton budget per pressure, default 20).
        The curve that reaches the highest pressure is kept; ``mesh_fallback`` in
        its rows says whether it is a fallback's, the metadata which one
        (``mesh_fallback_kept``, from 1) and the first solve's reason.

    Returns
    -------
    Curve
    """
    from skinsuction.provenance import collect

    params = parse_point_id(pid)
    curve, kept, first_reason = solve_with_fallbacks(params, pressures_mbar, mesh, fallback,
                                                     label=f"point {pid}")
    meta = {"mesh": mesh, "mesh_fallback": fallback, "provenance": collect(), **(metadata or {})}
    if kept:
        meta["mesh_fallback_kept"] = kept
    if first_reason is not None:
        meta["first_solve_reason"] = first_reason
    write_curve(curve, params, path, meta)
    return curve


class CorruptCurveError(ValueError):
    """A curve file cannot be read (truncated or overwritten): its name and the remedy."""


def read_curve(path) -> tuple[pd.DataFrame, dict]:
    """Rows and metadata of one curve file written by :func:`write_curve`.

    A file that cannot be read (truncated by a full disk or a copy, overwritten)
    raises :class:`CorruptCurveError` naming it: curve files are written
    atomically, so a killed job never leaves one; delete it and rerun.
    """
    try:
        return _read_parquet(path)
    except (OSError, ValueError) as err:  # pyarrow: ArrowInvalid is a ValueError
        raise CorruptCurveError(
            f"{path}: unreadable curve file ({type(err).__name__}: "
            f"{' '.join(str(err).split())[:160]}); delete it and rerun the workflow "
            "to recompute it") from None


def read_curves(paths) -> tuple[pd.DataFrame, dict]:
    """Concatenated rows of several curve files and their metadata by point id."""
    frames, metas = [], {}
    for path in paths:
        frame, meta = read_curve(path)
        pid = meta.get("point_id", str(path))
        if pid in metas:
            raise ValueError(f"grid point {pid} given twice (second time: {path})")
        frames.append(frame)
        metas[pid] = meta
    if not frames:
        raise ValueError("no curve files given")
    frame = pd.concat(frames, ignore_index=True)
    return frame, metas


def _sorted(frame: pd.DataFrame) -> pd.DataFrame:
    keys = ["probe_mm", "bottom", "x2d", "x2h", "t_d", "t_h", "x1d", "x1h", "pressure_mbar"]
    return frame.sort_values(keys, kind="stable").reset_index(drop=True)


def assemble_space(curve_paths, out_path, config: dict, name: str) -> "SimulatedSpace":
    """Assemble the curve files of one space into its database (atomic Parquet).

    Every grid point is kept: a point whose solve stopped early keeps its rows
    with ``converged=False`` and NaN deflections beyond ``last_converged_mbar``.
    The schema metadata holds a JSON provenance record (see
    :func:`skinsuction.provenance.collect`) with the configuration, the mesh
    settings, the pressures, package versions, git commit and per-point solver
    information.

    Parameters
    ----------
    curve_paths : iterable of path-like
        Curve files of the space (one per grid point).
    out_path : path-like
        Database file, conventionally ``results/simulated_space/<name>.parquet``.
    config : dict
        The validated study configuration.
    name : str
        Name of the space in ``config["spaces"]``.
    """
    from skinsuction.provenance import collect

    frame, metas = read_curves(curve_paths)
    counts = frame.groupby("point_id")["pressure_mbar"].count()
    frame = _sorted(frame)
    points = frame.drop_duplicates("point_id")
    job_versions = []
    per_point = {}
    for pid, meta in metas.items():
        prov = meta.get("provenance", {}) or {}
        per_point[pid] = {
            "curve_info": meta.get("curve_info", {}),
            "created_utc": prov.get("created_utc"),
            "git_commit": (prov.get("git") or {}).get("commit"),
            "source_hash": meta.get("source_hash"),
        }
        if prov.get("versions") and prov["versions"] not in job_versions:
            job_versions.append(prov["versions"])
    meta = collect(
        config=config,
        space=name,
        spec=(config.get("spaces") or {}).get(name),
        mesh=config.get("mesh"),
        pressures_mbar=sorted(frame["pressure_mbar"].unique().tolist()),
        n_points=int(len(points)),
        n_converged=int(points["converged"].sum()),
        rows_per_point=sorted(set(counts.tolist())),
        job_versions=job_versions,
        points=per_point,
    )
    _write_parquet(frame, out_path, meta)
    log.info(
        "space %s: %d points, %d converged -> %s",
        name,
        len(points),
        int(points["converged"].sum()),
        out_path,
    )
    return SimulatedSpace(frame, meta)


# -------------------------------------------------------------------- the database
@dataclass
class SimulatedSpace:
    """A simulated space: FE suction curves on a parameter grid.

    Attributes
    ----------
    frame : pandas.DataFrame
        Long format, one row per grid point and pressure, columns :data:`COLUMNS`.
    metadata : dict
        Provenance record (configuration, versions, git commit, ...).

    Examples
    --------
    >>> space = read_space("results/simulated_space/paper.parquet")  # doctest: +SKIP
    >>> x1d, x1h, p, M = space.grid(6.0)                             # doctest: +SKIP
    >>> M.shape                                                      # doctest: +SKIP
    (11, 11, 51)
    """

    frame: pd.DataFrame
    metadata: dict = field(default_factory=dict)

    @property
    def points(self) -> pd.DataFrame:
        """One row per grid point (the pressure-independent columns)."""
        cols = [c for c in COLUMNS if c not in ("pressure_mbar", "deflection_mm")]
        return self.frame.drop_duplicates("point_id")[cols].reset_index(drop=True)

    def slices(self) -> pd.DataFrame:
        """The available (probe, bottom, X2d, X2h, t_d, t_h) combinations."""
        keys = ["probe_mm", "bottom", "x2d", "x2h", "t_d", "t_h"]
        return self.frame[keys].drop_duplicates().sort_values(keys).reset_index(drop=True)

    def grid(
        self,
        probe_mm,
        bottom="fixed",
        x2d=0.0,
        x2h=0.0,
        t_d=1.0,
        t_h=1.0,
        *,
        partial=True,
    ):
        """The (X1d, X1h, p) grid of deflections for one aperture and condition.

        Parameters
        ----------
        probe_mm : float
            Aperture (probe) diameter in mm.
        bottom : {"fixed", "axial", "free"}
            Boundary condition at the hypodermis/bone interface.
        x2d, x2h : float
            Second-order moduli (MPa) of dermis and hypodermis.
        t_d, t_h : float
            Dermis and hypodermis thickness (mm).
        partial : bool, keyword-only
            If True (default), a non-converged point keeps its deflections up to
            its last converged pressure; if False, the whole curve is NaN.

        Returns
        -------
        x1d : ndarray, shape (n1,)
            Dermis moduli X1d (MPa), ascending.
        x1h : ndarray, shape (n2,)
            Hypodermis moduli X1h (MPa), ascending.
        pressure_mbar : ndarray, shape (np,)
            Pressures (mbar), ascending.
        deflection_mm : ndarray, shape (n1, n2, np)
            Apex deflection M (mm); NaN where the solver did not converge or the
            point is missing from the database.

        Raises
        ------
        KeyError
            If the database has no point for this combination.
        """
        f = self.frame
        sel = (
            np.isclose(f["probe_mm"].to_numpy(float), float(probe_mm), rtol=1e-9, atol=0)
            & (f["bottom"].to_numpy() == bottom)
            & np.isclose(f["x2d"].to_numpy(float), float(x2d), rtol=1e-9, atol=1e-300)
            & np.isclose(f["x2h"].to_numpy(float), float(x2h), rtol=1e-9, atol=1e-300)
            & np.isclose(f["t_d"].to_numpy(float), float(t_d), rtol=1e-9, atol=0)
            & np.isclose(f["t_h"].to_numpy(float), float(t_h), rtol=1e-9, atol=0)
        )
        sub = f[sel]
        if sub.empty:
            raise KeyError(
                f"no points for probe_mm={probe_mm}, bottom={bottom!r}, x2d={x2d}, "
                f"x2h={x2h}, t_d={t_d}, t_h={t_h}; available:\n{self.slices()}"
            )
        x1d = np.unique(sub["x1d"].to_numpy(float))
        x1h = np.unique(sub["x1h"].to_numpy(float))
        p = np.unique(sub["pressure_mbar"].to_numpy(float))
        out = np.full((x1d.size, x1h.size, p.size), np.nan)
        i = np.searchsorted(x1d, sub["x1d"].to_numpy(float))
        j = np.searchsorted(x1h, sub["x1h"].to_numpy(float))
        k = np.searchsorted(p, sub["pressure_mbar"].to_numpy(float))
        conv = sub["converged"].to_numpy(bool)
        if partial:
            last = sub["last_converged_mbar"].to_numpy(float)
            valid = conv | (sub["pressure_mbar"].to_numpy(float) <= last)
        else:
            valid = conv
        out[i[valid], j[valid], k[valid]] = sub["deflection_mm"].to_numpy(float)[valid]
        return x1d, x1h, p, out

    def convergence_summary(self) -> pd.DataFrame:
        """Converged point counts per probe and bottom condition."""
        return convergence_summary(self.frame)


def read_space(path) -> SimulatedSpace:
    """Read a simulated-space database written by :func:`assemble_space`."""
    frame, meta = _read_parquet(path)
    return SimulatedSpace(frame, meta)


def convergence_summary(frame: pd.DataFrame) -> pd.DataFrame:
    """Per (probe, bottom): number of points, converged, failed, solver effort.

    Columns: ``probe_mm, bottom, n_points, n_converged, n_failed, n_fallback``
    (points whose kept curve is the fallback mesh's), ``fraction_converged,
    min_last_converged_mbar, newton_iterations_median,
    dofs_median, seconds_median, seconds_total, reasons`` (failure reasons with
    their counts).
    """
    pts = frame.drop_duplicates("point_id")
    rows = []
    for (probe, bottom), g in pts.groupby(["probe_mm", "bottom"], sort=True):
        failed = g[~g["converged"].astype(bool)]
        reasons = failed["reason"].replace("", "unknown").value_counts()
        rows.append(
            {
                "probe_mm": probe,
                "bottom": bottom,
                "n_points": len(g),
                "n_converged": int(g["converged"].sum()),
                "n_failed": len(failed),
                "n_fallback": int(g.get("mesh_fallback", pd.Series(False, g.index)).sum()),
                "fraction_converged": float(g["converged"].mean()),
                "min_last_converged_mbar": float(g["last_converged_mbar"].min()),
                "newton_iterations_median": float(g["newton_iterations"].median()),
                "dofs_median": float(g["dofs"].median()),
                "seconds_median": float(g["seconds"].median()),
                "seconds_total": float(g["seconds"].sum()),
                "reasons": "; ".join(f"{r} ({n})" for r, n in reasons.items()),
            }
        )
    return pd.DataFrame(rows)


def write_table(frame: pd.DataFrame, path) -> Path:
    """Write a results table as CSV, atomically."""
    with atomic_output(path) as tmp:
        frame.to_csv(tmp, index=False)
    return Path(path)
