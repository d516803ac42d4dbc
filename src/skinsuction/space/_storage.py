"""Storage of FE curves: point ids, curve files and Parquet with provenance.

Every grid point (and every ray, :mod:`._rays`) has a readable, unique id
(:func:`point_id`, :func:`parse_point_id`) and one curve file
(:func:`write_curve`, :func:`read_curve`): long-format rows, one per pressure,
with the JSON provenance record in the Parquet schema metadata.  Values are
rounded to 12 significant digits so that ids are free of floating-point
round-off.

Examples
--------
>>> pid = point_id({"probe_mm": 6, "x1d": 0.08, "x1h": 0.00041})
>>> pid
'p6_fixed_x1d0.08_x1h0.00041_x2d0_x2h0_td1_th1'
>>> parse_point_id(pid)["x1h"]
0.00041
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pandas as pd

from skinsuction._files import atomic_output


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

#: The parameter path of the skin (:class:`skinsuction.model.Skin`, the paper's
#: dermis over hypodermis) that each numeric grid axis sets: the axes, the point
#: and ray ids and the stored columns keep the two-layer keywords (they are data).
AXIS_PATHS = {
    "x1d": "dermis.X1",
    "x1h": "hypodermis.X1",
    "x2d": "dermis.X2",
    "x2h": "hypodermis.X2",
    "t_d": "dermis.thickness",
    "t_h": "hypodermis.thickness",
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

    Parameters
    ----------
    value : float
    digits : int

    Returns
    -------
    float

    Examples
    --------
    >>> round_sig(0.001 + 10 * 0.009)
    0.091
    """
    return float(f"{float(value):.{digits}g}") + 0.0


def _is_number(x) -> bool:
    return isinstance(x, (int, float, np.integer, np.floating)) and not isinstance(
        x, (bool, np.bool_)
    )


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
#: Regular expression for row ids (:func:`row_id`).
ROW_ID_PATTERN = r"p[^/_]+_[a-z]+_x1d[^/_]+_x2d[^/_]+_x2h[^/_]+_td[^/_]+_th[^/_]+"


def point_id(params: dict) -> str:
    """Readable unique name of a grid point, used in file names.

    Numbers are written with 12 significant digits (``%.12g``), so the id is
    exact for grid values (which :func:`expand_axis` rounds to 12 digits).

    Parameters
    ----------
    params : dict
        The point's axes (:data:`AXES`, the two-layer keywords; those missing at
        :data:`DEFAULTS`).

    Returns
    -------
    str

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


def row_id(pid: str) -> str:
    """The row of the grid a point lies on: its id without X1h.

    The workflow solves a row (one probe, bottom, X1d and layers, every X1h) in one
    job and one file (:func:`write_curves`): a point costs 0.6 s of FE, a job of its
    own some 2 s more of start-up and bookkeeping.

    Examples
    --------
    >>> row_id("p6_fixed_x1d0.08_x1h1e-05_x2d0_x2h0_td1_th1")
    'p6_fixed_x1d0.08_x2d0_x2h0_td1_th1'
    """
    parse_point_id(pid)  # a clear error for what is no point id
    return re.sub(r"_x1h[^_]+", "", pid, count=1)


def parse_point_id(pid: str) -> dict:
    """The grid point parameters encoded in a point id (inverse of :func:`point_id`).

    Parameters
    ----------
    pid : str

    Returns
    -------
    dict
        One value per axis of :data:`AXES`.

    Examples
    --------
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

    Parameters
    ----------
    curve : skinsuction.model.Curve
    params : dict
        The point's axes (:data:`AXES`; those missing at :data:`DEFAULTS`).

    Returns
    -------
    pandas.DataFrame
        Columns :data:`COLUMNS`.
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

    Returns
    -------
    Path
        The file written.
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


def write_curves(points, path, metadata: dict | None = None) -> Path:
    """Write the FE curves of several grid points to one Parquet file (atomically).

    Parameters
    ----------
    points : iterable of (curve, params, dict)
        Each point's curve (a failed one too), its axes and its own metadata (as
        :func:`write_curve` takes them).
    path : path-like
        Output file, conventionally ``results/curves/<row_id>.parquet``.
    metadata : dict, optional
        Provenance shared by every point (the mesh, versions, source hash).

    Returns
    -------
    Path
        The file written; :func:`read_curves` gives each point back with the
        metadata :func:`write_curve` would have stored.
    """
    frames, per_point = [], {}
    for curve, params, own in points:
        frame = curve_frame(curve, params)
        pid = frame["point_id"].iloc[0]
        if pid in per_point:
            raise ValueError(f"grid point {pid} given twice")
        frames.append(frame)
        per_point[pid] = {
            "point": {k: params.get(k, DEFAULTS.get(k, [None])[0]) for k in AXES},
            "curve_info": dict(getattr(curve, "info", {}) or {}),
            **(own or {}),
        }
    if not frames:
        raise ValueError(f"{path}: no curves to write")
    _write_parquet(pd.concat(frames, ignore_index=True), path,
                   {**(metadata or {}), "points": per_point})
    return Path(path)


class CorruptCurveError(ValueError):
    """A curve file cannot be read (truncated or overwritten): its name and the remedy."""


def read_curve(path) -> tuple[pd.DataFrame, dict]:
    """Rows and metadata of one curve file written by :func:`write_curve`.

    A file that cannot be read (truncated by a full disk or a copy, overwritten)
    raises :class:`CorruptCurveError` naming it: curve files are written
    atomically, so a killed job never leaves one; delete it and rerun.

    Parameters
    ----------
    path : path-like

    Returns
    -------
    frame : pandas.DataFrame
    metadata : dict
    """
    try:
        return _read_parquet(path)
    except (OSError, ValueError) as err:  # pyarrow: ArrowInvalid is a ValueError
        raise CorruptCurveError(
            f"{path}: unreadable curve file ({type(err).__name__}: "
            f"{' '.join(str(err).split())[:160]}); delete it and rerun the workflow "
            "to recompute it") from None


def read_curves(paths, points=None) -> tuple[pd.DataFrame, dict]:
    """Concatenated rows of several curve files and their metadata by point id.

    A file of several points (:func:`write_curves`) gives each point with the
    metadata :func:`write_curve` would have stored for it alone.

    Parameters
    ----------
    paths : iterable of path-like
    points : iterable of str, optional
        Keep only these point ids (a row's file may hold points of other spaces);
        each one must be found.

    Returns
    -------
    frame : pandas.DataFrame
    metadata : dict
        ``{point_id: metadata}``.

    Raises
    ------
    ValueError
        If no file is given, a point is given twice or a point asked for is in no file.
    """
    paths = list(paths)
    frames, metas = [], {}
    for path in paths:
        frame, meta = read_curve(path)
        shared = {k: v for k, v in meta.items() if k != "points"}
        own = meta["points"] if "points" in meta else {meta.get("point_id", str(path)): {}}
        for pid, extra in own.items():
            if pid in metas:
                raise ValueError(f"grid point {pid} given twice (second time: {path})")
            metas[pid] = {**shared, "point_id": pid, **extra}
        frames.append(frame)
    if not frames:
        raise ValueError("no curve files given")
    frame = pd.concat(frames, ignore_index=True)
    if points is not None:
        points = list(points)
        missing = sorted(set(points) - set(metas))
        if missing:
            raise ValueError(f"grid point {missing[0]} is in none of the curve files "
                             f"{', '.join(map(str, paths[:3]))}{' ...' if len(paths) > 3 else ''}"
                             f" ({len(missing)} missing); rerun the workflow to recompute them")
        frame = frame[frame["point_id"].isin(points)].reset_index(drop=True)
        metas = {pid: metas[pid] for pid in points}
    return frame, metas


def _sorted(frame: pd.DataFrame) -> pd.DataFrame:
    keys = ["probe_mm", "bottom", "x2d", "x2h", "t_d", "t_h", "x1d", "x1h", "pressure_mbar"]
    return frame.sort_values(keys, kind="stable").reset_index(drop=True)
