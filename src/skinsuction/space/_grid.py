"""The paper's layout of the simulated space: a grid of FE curves (paper eq. 2-3).

The paper (section 2.3) precomputes the apex deflection M(x, p, v) on a grid of
material parameters x = (X1d, X1h) and pressures p, for a given aperture (probe
diameter).  This module expands the grid specifications of the configuration
(:func:`expand_axis`, :func:`grid_points`), assembles the curve files of a space
(:mod:`._storage`) into one long-format database with provenance
(:func:`assemble_space`) and reads it back as a :class:`SimulatedSpace`, whose
:meth:`SimulatedSpace.grid` gives the dense arrays of one probe
(:class:`skinsuction.space.GriddedSpace`).

A grid axis is specified as a number, a list of values, a range
``{start, stop, step}`` (both ends included) or ``{logspace: [a, b, n]}``
(``n`` values from ``10**a`` to ``10**b``). Values are rounded to 12 significant
digits so that ranges are free of floating-point round-off.

Examples
--------
>>> expand_axis({"start": 0.001, "stop": 0.091, "step": 0.009})[-1]
0.091
>>> pts = grid_points({"probes_mm": [6], "x1d": [0.08], "x1h": [0.00041]})
>>> pts[0]["x1d"], pts[0]["bottom"], pts[0]["t_d"]
(0.08, 'fixed', 1.0)
"""

from __future__ import annotations

import itertools
import logging
import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ._storage import (
    AXES,
    AXIS_PATHS,
    BOTTOMS,
    COLUMNS,
    DEFAULTS,
    SPEC_KEYS,
    _is_number,
    _read_parquet,
    _sorted,
    _write_parquet,
    read_curves,
    round_sig,
)

log = logging.getLogger(__name__)


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


def assemble_space(curve_paths, out_path, config: dict, name: str, points=None) -> "SimulatedSpace":
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
        Curve files of the space (one per grid point, or one per row of the grid).
    out_path : path-like
        Database file, conventionally ``results/simulated_space/<name>.parquet``.
    config : dict
        The validated study configuration.
    name : str
        Name of the space in ``config["spaces"]``.
    points : iterable of str, optional
        The space's point ids, when the files hold other points too (a row
        shared with Figure 3); each one must be found.

    Returns
    -------
    SimulatedSpace
        The database as written.
    """
    from skinsuction.provenance import collect

    frame, metas = read_curves(curve_paths, points)
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
        """The available (probe, bottom, X2d, X2h, t_d, t_h) combinations.

        Returns
        -------
        pandas.DataFrame
            Columns ``probe_mm, bottom, x2d, x2h, t_d, t_h`` (the stored columns),
            one row per slice.
        """
        keys = ["probe_mm", "bottom", "x2d", "x2h", "t_d", "t_h"]
        return self.frame[keys].drop_duplicates().sort_values(keys).reset_index(drop=True)

    def grid(self, probe_mm, values=None, *, bottom="fixed", partial=True):
        """The (X1d, X1h, p) grid of deflections for one aperture and condition.

        Parameters
        ----------
        probe_mm : float
            Aperture (probe) diameter in mm.
        values : mapping, optional
            The values of the other axes, by parameter path of the skin
            (:data:`SLICE_PATHS`): ``dermis.X2``, ``hypodermis.X2`` (MPa),
            ``dermis.thickness``, ``hypodermis.thickness`` (mm).  A path not
            given is at its default (0 MPa, 1 mm: the paper's).
        bottom : {"fixed", "axial", "free"}, keyword-only
            Boundary condition at the hypodermis/bone interface.
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
        ValueError
            For a path of ``values`` that is not one of :data:`SLICE_PATHS`.

        Examples
        --------
        >>> space.grid(6.0, {"dermis.thickness": 1.3})                # doctest: +SKIP
        """
        x2d, x2h, t_d, t_h = _slice_values(values)
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
        """Converged point counts per probe and bottom condition.

        Returns
        -------
        pandas.DataFrame
            As :func:`convergence_summary`.
        """
        return convergence_summary(self.frame)


#: The grid axes a slice of the database fixes besides the probe and the bottom, by the
#: parameter path of the skin (:data:`skinsuction.space.AXIS_PATHS`), in the order x2d,
#: x2h, t_d, t_h.
SLICE_PATHS = tuple(AXIS_PATHS[key] for key in ("x2d", "x2h", "t_d", "t_h"))


def _slice_values(values) -> tuple:
    """``(x2d, x2h, t_d, t_h)`` of a mapping by parameter path, defaults where not given."""
    values = dict(values or {})
    unknown = sorted(set(values) - set(SLICE_PATHS))
    if unknown:
        raise ValueError(f"{unknown}: not an axis of a slice of the grid; its axes are "
                         f"{list(SLICE_PATHS)}")
    keys = ("x2d", "x2h", "t_d", "t_h")
    return tuple(float(values.get(path, DEFAULTS[key][0])) for path, key in zip(SLICE_PATHS, keys))


def read_space(path) -> SimulatedSpace:
    """Read a simulated-space database written by :func:`assemble_space`.

    Parameters
    ----------
    path : path-like

    Returns
    -------
    SimulatedSpace
    """
    frame, meta = _read_parquet(path)
    return SimulatedSpace(frame, meta)


def convergence_summary(frame: pd.DataFrame) -> pd.DataFrame:
    """Per (probe, bottom): number of points, converged, failed, solver effort.

    Parameters
    ----------
    frame : pandas.DataFrame
        A database's rows (:attr:`SimulatedSpace.frame`).

    Returns
    -------
    pandas.DataFrame
        Columns ``probe_mm, bottom, n_points, n_converged, n_failed, n_fallback``
        (points whose kept curve is the fallback mesh's), ``fraction_converged,
        min_last_converged_mbar, newton_iterations_median, dofs_median,
        seconds_median, seconds_total, reasons`` (failure reasons with their
        counts).
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
