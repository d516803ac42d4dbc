"""Simulated-space database: grid axes, point ids, curve files, assembly, grid()."""

import dataclasses
import json
import sys
import types

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from skinsuction.model import ParameterError, Skin
from skinsuction import provenance, space
from skinsuction.space import COLUMNS, SimulatedSpace, assemble_space, compute_point, compute_points, expand_axis, grid_points, parse_point_id, point_id, read_curve, read_curves, read_space, round_sig, row_id, write_curve
from skinsuction._files import atomic_output

PAPER = {
    "probes_mm": [2, 6],
    "bottom": ["fixed"],
    "x1d": {"start": 0.001, "stop": 0.091, "step": 0.009},
    "x1h": {"start": 1.0e-5, "stop": 2.01e-3, "step": 2.0e-4},
}


@dataclasses.dataclass
class StandInCurve:
    """Stand-in with the attributes of skinsuction.model.Curve (for plumbing only)."""

    pressure_mbar: np.ndarray
    deflection_mm: np.ndarray
    converged: bool
    last_converged_mbar: float
    reason: str = ""
    newton_iterations: int = 0
    dofs: int = 0
    seconds: float = 0.0
    info: dict = dataclasses.field(default_factory=dict)


def stand_in_curve(params, pressures, fail_above=None):
    """Deflection growing with pressure, softer for smaller moduli; optionally fails."""
    p = np.asarray(pressures, float)
    m = 0.01 * params["probe_mm"] * np.sqrt(p) / (params["x1d"] * 50 + params["x1h"] * 500) ** 0.3
    if fail_above is None:
        return StandInCurve(p, m, True, float(p[-1]), "", 3 * len(p), 1234, 0.5, {"stand_in": True})
    ok = p <= fail_above
    return StandInCurve(
        p, np.where(ok, m, np.nan), False, float(p[ok][-1]), "newton diverged", 40, 1234, 0.7
    )


# ------------------------------------------------------------------------- axes
def test_paper_axes_have_11_values_with_exact_endpoints():
    x1d = expand_axis(PAPER["x1d"])
    x1h = expand_axis(PAPER["x1h"])
    assert len(x1d) == 11 and len(x1h) == 11
    assert x1d[0] == 0.001 and x1d[-1] == 0.091
    assert x1h[0] == 1e-5 and x1h[-1] == 2.01e-3
    assert x1d[1] == 0.01 and x1h[2] == 0.00041  # values named in the paper
    p = expand_axis({"start": 0, "stop": 100, "step": 2})
    assert len(p) == 51 and p[0] == 0.0 and p[-1] == 100.0


def test_logspace_scalar_and_list_axes():
    ax = expand_axis({"logspace": [-5, -1, 13]})
    assert len(ax) == 13 and ax[0] == 1e-5 and ax[-1] == 0.1 and ax[3] == 1e-4
    assert expand_axis(0.08) == [0.08]
    assert expand_axis([6, 2]) == [6.0, 2.0]
    assert expand_axis(["fixed", "free"]) == ["fixed", "free"]


@pytest.mark.parametrize(
    "spec",
    [
        [],
        [1.0, 1.0],
        {"start": 1, "stop": 0, "step": 0.1},
        {"start": 0, "stop": 1, "step": 0},
        {"start": 0, "stop": 1},
        {"logspace": [-5, -1, 0]},
        {"values": [1]},
        [float("nan")],
        None,
    ],
)
def test_bad_axes_are_refused(spec):
    with pytest.raises(ValueError):
        expand_axis(spec)


@settings(max_examples=200, deadline=None)
@given(
    start=st.decimals(min_value="0", max_value="10", places=4),
    step=st.decimals(min_value="0.0001", max_value="5", places=4),
    n=st.integers(min_value=1, max_value=60),
)
def test_range_has_exact_length_and_endpoint(start, step, n):
    stop = start + (n - 1) * step  # exact in decimal, rounded in binary
    ax = expand_axis({"start": float(start), "stop": float(stop), "step": float(step)})
    assert len(ax) == n
    assert ax[-1] == round_sig(float(stop))
    assert ax == sorted(ax)


def test_grid_points_count_order_and_defaults():
    pts = grid_points(PAPER)
    assert len(pts) == 242
    assert pts[0] == dict(probe_mm=2.0, bottom="fixed", x1d=0.001, x1h=1e-5, x2d=0.0, x2h=0.0, t_d=1.0, t_h=1.0)
    assert pts[1]["x1h"] == 0.00021  # X1h varies fastest among the material axes
    assert len({point_id(p) for p in pts}) == 242
    more = grid_points({**PAPER, "x2d": [0.0, 0.01], "t_h": {"start": 1, "stop": 3, "step": 1}})
    assert len(more) == 242 * 2 * 3
    with pytest.raises(ValueError, match="unknown"):
        grid_points({**PAPER, "x3": [1]})
    with pytest.raises(ValueError, match="bottom"):
        grid_points({**PAPER, "bottom": ["glued"]})
    assert len(grid_points({**PAPER, "pressure_mbar": 100}, ignore=("pressure_mbar",))) == 242


# ---------------------------------------------------------------------- point ids
def test_point_id_is_readable():
    pid = point_id(dict(probe_mm=6, bottom="fixed", x1d=0.08, x1h=0.00041, x2d=0, x2h=0, t_d=1, t_h=1))
    assert pid == "p6_fixed_x1d0.08_x1h0.00041_x2d0_x2h0_td1_th1"


_value = st.floats(min_value=1e-9, max_value=1e4, allow_nan=False).map(round_sig)


@settings(max_examples=300, deadline=None)
@given(
    probe=_value,
    bottom=st.sampled_from(space.BOTTOMS),
    x1d=_value,
    x1h=_value,
    x2d=st.floats(min_value=-10, max_value=10, allow_nan=False).map(round_sig),
    x2h=st.floats(min_value=-10, max_value=10, allow_nan=False).map(round_sig),
    t_d=_value,
    t_h=_value,
)
def test_point_id_round_trip(probe, bottom, x1d, x1h, x2d, x2h, t_d, t_h):
    params = dict(probe_mm=probe, bottom=bottom, x1d=x1d, x1h=x1h, x2d=x2d, x2h=x2h, t_d=t_d, t_h=t_h)
    pid = point_id(params)
    assert "/" not in pid and " " not in pid
    assert parse_point_id(pid) == params
    import re

    assert re.fullmatch(space.POINT_ID_PATTERN, pid)


@pytest.mark.parametrize("bad", ["", "p6_fixed", "p6_glued_x1d1_x1h1_x2d0_x2h0_td1_th1", "p6_fixed_x1dabc_x1h1_x2d0_x2h0_td1_th1"])
def test_parse_point_id_refuses_garbage(bad):
    with pytest.raises(ValueError):
        parse_point_id(bad)


# -------------------------------------------------------------- curves and spaces
PRESSURES = np.arange(0, 101, 10.0)


def _write_points(tmp_path, points, fail=()):
    paths = []
    for params in points:
        pid = point_id(params)
        curve = stand_in_curve(params, PRESSURES, fail_above=40.0 if pid in fail else None)
        path = tmp_path / "curves" / f"{pid}.parquet"
        write_curve(curve, params, path, {"provenance": provenance.collect(), "source_hash": {"model": "abc"}})
        paths.append(path)
    return paths


@pytest.fixture
def small_space(tmp_path):
    spec = {"probes_mm": [2, 6], "x1d": [0.01, 0.05, 0.09], "x1h": [1e-5, 1e-3]}
    points = grid_points(spec)
    failed = point_id(points[4])  # probe 2, x1d 0.05... one non-converged point
    config = {"spaces": {"small": spec}, "mesh": {"refinement": 0.5}, "pressures_mbar": [0, 100]}
    paths = _write_points(tmp_path, points, fail={failed})
    out = tmp_path / "simulated_space" / "small.parquet"
    assemble_space(paths, out, config, "small")
    return out, points, failed


def test_curve_file_round_trip(tmp_path):
    params = grid_points({"probes_mm": 6, "x1d": 0.08, "x1h": 1e-4})[0]
    path = tmp_path / "c.parquet"
    write_curve(stand_in_curve(params, PRESSURES), params, path, {"note": "x"})
    frame, meta = read_curve(path)
    assert list(frame.columns) == list(COLUMNS)
    assert len(frame) == len(PRESSURES)
    assert frame["converged"].all() and (frame["point_id"] == point_id(params)).all()
    assert meta["point"] == params and meta["note"] == "x" and meta["curve_info"] == {"stand_in": True}


def test_assembly_keeps_failed_points(small_space):
    out, points, failed = small_space
    s = read_space(out)
    assert list(s.frame.columns) == list(COLUMNS)
    assert s.frame["point_id"].nunique() == len(points) == 12
    assert len(s.frame) == 12 * len(PRESSURES)
    bad = s.frame[s.frame["point_id"] == failed]
    assert len(bad) == len(PRESSURES)
    assert not bad["converged"].any()
    assert (bad["last_converged_mbar"] == 40.0).all()
    assert bad["reason"].iloc[0] == "newton diverged"
    assert bad.loc[bad["pressure_mbar"] > 40, "deflection_mm"].isna().all()
    assert bad.loc[bad["pressure_mbar"] <= 40, "deflection_mm"].notna().all()
    assert s.points["converged"].sum() == 11


def test_provenance_metadata_present(small_space):
    out, points, failed = small_space
    meta = read_space(out).metadata
    assert meta["space"] == "small"
    assert meta["config"]["mesh"] == {"refinement": 0.5}
    assert meta["mesh"] == {"refinement": 0.5}
    assert meta["n_points"] == 12 and meta["n_converged"] == 11
    for pkg in ("felupe", "numpy", "scipy", "pandas", "pyarrow", "skinsuction", "python"):
        assert meta["versions"][pkg], pkg
    assert "commit" in meta["git"] and "dirty" in meta["git"]
    assert meta["created_utc"].endswith("+00:00")
    assert meta["points"][failed]["source_hash"] == {"model": "abc"}
    assert meta["job_versions"] and meta["pressures_mbar"] == PRESSURES.tolist()
    # the record is plain JSON in the Parquet schema metadata, readable without skinsuction
    raw = pq.read_schema(out).metadata[b"skinsuction"]
    assert json.loads(raw)["space"] == "small"


def test_grid_shape_and_nan_for_failed_points(small_space):
    out, points, failed = small_space
    s = read_space(out)
    x1d, x1h, p, m = s.grid(2.0)
    assert x1d.tolist() == [0.01, 0.05, 0.09] and x1h.tolist() == [1e-5, 1e-3]
    assert np.array_equal(p, PRESSURES)
    assert m.shape == (3, 2, len(PRESSURES))
    fp = parse_point_id(failed)
    i, j = x1d.tolist().index(fp["x1d"]), x1h.tolist().index(fp["x1h"])
    assert np.isnan(m[i, j, p > 40]).all() and np.isfinite(m[i, j, p <= 40]).all()
    assert np.isfinite(np.delete(m.reshape(6, -1), i * 2 + j, axis=0)).all()
    _, _, _, m_strict = s.grid(2.0, partial=False)
    assert np.isnan(m_strict[i, j]).all()
    # the 6 mm aperture has no failure; deflection grows with pressure
    m6 = s.grid(6, {"dermis.X2": 0.0, "hypodermis.X2": 0.0, "dermis.thickness": 1.0,
                    "hypodermis.thickness": 1.0}, bottom="fixed")[3]
    assert np.isfinite(m6).all() and (np.diff(m6, axis=2) > 0).all()
    assert np.array_equal(m6, s.grid(6.0)[3], equal_nan=True)  # the paths' defaults
    with pytest.raises(KeyError, match="available"):
        s.grid(4.0)
    with pytest.raises(KeyError, match="t_d=1.3"):
        s.grid(6.0, {"dermis.thickness": 1.3})
    with pytest.raises(ValueError, match="not an axis of a slice"):
        s.grid(6.0, {"t_d": 1.0})


def test_grid_marks_missing_points_nan(small_space):
    out, points, failed = small_space
    s = read_space(out)
    drop = point_id(points[0])
    holes = SimulatedSpace(s.frame[s.frame["point_id"] != drop].reset_index(drop=True), s.metadata)
    m = holes.grid(2.0)[3]
    assert m.shape == (3, 2, len(PRESSURES)) and np.isnan(m[0, 0]).all()


def test_convergence_summary(small_space):
    out, points, failed = small_space
    summary = read_space(out).convergence_summary()
    assert summary[["probe_mm", "n_points", "n_converged", "n_failed"]].values.tolist() == [
        [2.0, 6, 5, 1],
        [6.0, 6, 6, 0],
    ]
    assert summary.loc[0, "reasons"] == "newton diverged (1)"


def test_assembly_refuses_duplicate_points(tmp_path):
    params = grid_points({"probes_mm": 6, "x1d": 0.08, "x1h": 1e-4})[0]
    (path,) = _write_points(tmp_path, [params])
    with pytest.raises(ValueError, match="twice"):
        assemble_space([path, path], tmp_path / "s.parquet", {"spaces": {}}, "s")


# --------------------------------------------------------------------- atomicity
def test_atomic_write_leaves_no_partial_file(tmp_path, monkeypatch):
    params = grid_points({"probes_mm": 6, "x1d": 0.08, "x1h": 1e-4})[0]
    target = tmp_path / "c.parquet"

    def broken_write(table, where, *a, **k):
        with open(where, "wb") as f:
            f.write(b"PAR1 half a file")
        raise OSError("disk full")

    monkeypatch.setattr(pq, "write_table", broken_write)
    with pytest.raises(OSError, match="disk full"):
        write_curve(stand_in_curve(params, PRESSURES), params, target)
    assert list(tmp_path.iterdir()) == []

    monkeypatch.undo()
    write_curve(stand_in_curve(params, PRESSURES), params, target)
    before = target.read_bytes()
    monkeypatch.setattr(pq, "write_table", broken_write)
    with pytest.raises(OSError):
        write_curve(stand_in_curve(params, PRESSURES, fail_above=20), params, target)
    assert target.read_bytes() == before  # the old file is intact
    assert [p.name for p in tmp_path.iterdir()] == ["c.parquet"]


def test_atomic_output_on_success_and_error(tmp_path):
    target = tmp_path / "sub" / "t.csv"
    with pytest.raises(RuntimeError):
        with atomic_output(target) as tmp:
            tmp.write_text("partial")
            raise RuntimeError
    assert not target.exists() and list((tmp_path / "sub").iterdir()) == []
    with atomic_output(target) as tmp:
        tmp.write_text("whole")
    assert target.read_text() == "whole"


# ------------------------------------------------------------ the FE job adapter
def stand_in_params(skin, probe_mm):
    """A stand-in model's view of the skin it is given: the flat two-layer values."""
    v = skin.two_layer_values()
    return dict(probe_mm=probe_mm, bottom=skin.bottom,
                **{k: v[k] for k in ("x1d", "x1h", "x2d", "x2h", "t_d", "t_h")})


@pytest.fixture
def stand_in_model(monkeypatch):
    """Replace skinsuction.model by a stand-in module for the duration of a test."""
    Curve = StandInCurve
    calls = []

    def simulate(skin, probe=6.0, pressures_mbar=None, mesh=None):
        params = stand_in_params(skin, probe)
        x1h = params["x1h"]
        calls.append((params, mesh))
        if x1h > 0.05:
            raise RuntimeError("mesh generator crashed")
        c = stand_in_curve(params, pressures_mbar)
        return Curve(c.pressure_mbar, c.deflection_mm, True, c.last_converged_mbar, dofs=10)

    fake = types.ModuleType("skinsuction.model")
    fake.Curve, fake.simulate, fake.ParameterError = Curve, simulate, ParameterError
    fake.Skin = Skin
    monkeypatch.setitem(sys.modules, "skinsuction.model", fake)
    return calls


def test_compute_point_writes_curve(tmp_path, stand_in_model):
    pid = "p6_axial_x1d0.08_x1h0.001_x2d0_x2h0_td1_th1.5"
    compute_point(pid, tmp_path / "c.parquet", PRESSURES, {"refinement": 0.5}, {"source_hash": {"model": "h"}})
    params, mesh = stand_in_model[0]
    assert params == parse_point_id(pid) and mesh == {"refinement": 0.5}
    frame, meta = read_curve(tmp_path / "c.parquet")
    assert frame["converged"].all() and (frame["dofs"] == 10).all()
    assert meta["mesh"] == {"refinement": 0.5} and meta["source_hash"] == {"model": "h"}
    assert meta["provenance"]["versions"]["felupe"]


def test_compute_point_records_a_model_exception_as_failed_point(tmp_path, stand_in_model):
    pid = "p6_fixed_x1d0.08_x1h0.1_x2d0_x2h0_td1_th1"
    compute_point(pid, tmp_path / "c.parquet", PRESSURES)
    frame, _ = read_curve(tmp_path / "c.parquet")
    assert len(frame) == len(PRESSURES)
    assert not frame["converged"].any() and frame["deflection_mm"].isna().all()
    assert frame["reason"].iloc[0].startswith("exception: RuntimeError: mesh generator crashed")


def test_a_row_in_one_file_reads_back_as_its_points_alone(tmp_path, stand_in_model):
    # the workflow solves a row of the grid in one job; every reader must see the same
    # points and per-point metadata as from one file a point
    row = [f"p6_fixed_x1d0.08_x1h{h}_x2d0_x2h0_td1_th1" for h in ("1e-05", "0.001", "0.1")]
    assert {row_id(pid) for pid in row} == {"p6_fixed_x1d0.08_x2d0_x2h0_td1_th1"}
    meta = {"source_hash": {"model": "h"}}
    compute_points(row, tmp_path / "row.parquet", PRESSURES, {"refinement": 0.5}, meta)
    alone = []
    for pid in row:
        compute_point(pid, tmp_path / f"{pid}.parquet", PRESSURES, {"refinement": 0.5}, meta)
        alone.append(tmp_path / f"{pid}.parquet")
    f_row, m_row = read_curves([tmp_path / "row.parquet"])
    f_one, m_one = read_curves(alone)
    cols = [c for c in COLUMNS if c != "seconds"]
    pd.testing.assert_frame_equal(f_row[cols], f_one[cols])
    assert sorted(m_row) == sorted(row) == sorted(m_one)
    for pid in row:  # the same record but for its time of creation
        a, b = (dict(m[pid], provenance=None) for m in (m_row, m_one))
        assert a == b and m_row[pid]["provenance"]["versions"] == m_one[pid]["provenance"]["versions"]
    # the model's exception is the third point's failure, recorded, not a lost row
    assert f_row.loc[f_row["point_id"] == row[2], "reason"].iloc[0].startswith("exception:")
    # a space picks its points out of a shared row, and misses none silently
    some, metas = read_curves([tmp_path / "row.parquet"], points=row[:2])
    assert set(some["point_id"]) == set(row[:2]) == set(metas)
    with pytest.raises(ValueError, match=r"p6_fixed_x1d0.08_x1h0.5_.*row.parquet"):
        read_curves([tmp_path / "row.parquet"], points=[row[0], row[1].replace("0.001", "0.5")])
    with pytest.raises(ValueError, match="given twice"):
        read_curves([tmp_path / "row.parquet", alone[0]])


@pytest.fixture
def stopping_model(monkeypatch):
    """Stand-in model whose solve stops at a pressure set per element type."""
    calls = []
    stops = {"quad8": 40.0, "quad9": None, "soft wall": None}

    def simulate(skin, probe=6.0, pressures_mbar=None, mesh=None, iteration_budget=None):
        params = stand_in_params(skin, probe)
        calls.append((mesh, iteration_budget))
        key = "soft wall" if "wall_penalty" in mesh else mesh.get("element", "quad8")
        return stand_in_curve(params, pressures_mbar, stops[key])

    fake = types.ModuleType("skinsuction.model")
    fake.Curve, fake.simulate, fake.ParameterError = StandInCurve, simulate, ParameterError
    fake.Skin = Skin
    monkeypatch.setitem(sys.modules, "skinsuction.model", fake)
    return calls, stops


FALLBACK = {"element": "quad9", "quadrature": "full", "iterations_per_step": 60}


def test_fallback_mesh_replaces_a_stopped_solve(tmp_path, stopping_model):
    calls, _ = stopping_model
    pid = "p6_fixed_x1d0.001_x1h1e-05_x2d0_x2h0_td1_th1"
    compute_point(pid, tmp_path / "c.parquet", PRESSURES, {"refinement": 0.5}, fallback=FALLBACK)
    # the second solve keeps the other settings and gets its own Newton budget
    assert calls == [({"refinement": 0.5}, None),
                     ({"refinement": 0.5, "element": "quad9", "quadrature": "full"},
                      60 * len(PRESSURES))]
    frame, meta = read_curve(tmp_path / "c.parquet")
    assert frame["converged"].all() and frame["mesh_fallback"].all()
    assert meta["first_solve_reason"] == "newton diverged"
    assert meta["mesh_fallback"] == FALLBACK and meta["mesh_fallback_kept"] == 1
    # both solves' time is accounted for
    assert frame["seconds"].iloc[0] == pytest.approx(0.7 + 0.5)


def test_fallback_that_stops_earlier_is_not_kept(tmp_path, stopping_model):
    calls, stops = stopping_model
    stops["quad9"] = 20.0
    pid = "p6_fixed_x1d0.001_x1h1e-05_x2d0_x2h0_td1_th1"
    compute_point(pid, tmp_path / "c.parquet", PRESSURES, {}, fallback=FALLBACK)
    frame, meta = read_curve(tmp_path / "c.parquet")
    assert len(calls) == 2 and not frame["mesh_fallback"].any()
    assert frame["last_converged_mbar"].iloc[0] == 40.0 and "first_solve_reason" not in meta


def test_fallbacks_are_tried_in_order_until_one_converges(tmp_path, stopping_model):
    calls, stops = stopping_model
    stops["quad9"] = 60.0
    chain = [FALLBACK, {**FALLBACK, "wall_penalty": 1.0}, {"element": "quad9"}]
    pid = "p2_fixed_x1d0.001_x1h1e-05_x2d0_x2h0_td1_th1"
    compute_point(pid, tmp_path / "c.parquet", PRESSURES, {}, fallback=chain)
    # the third is not tried: the second converged
    assert [mesh for mesh, _ in calls] == [
        {}, {"element": "quad9", "quadrature": "full"},
        {"element": "quad9", "quadrature": "full", "wall_penalty": 1.0},
    ]
    frame, meta = read_curve(tmp_path / "c.parquet")
    assert frame["converged"].all() and frame["mesh_fallback"].all()
    assert meta["mesh_fallback_kept"] == 2 and meta["first_solve_reason"] == "newton diverged"
    assert frame["seconds"].iloc[0] == pytest.approx(0.7 + 0.7 + 0.5)


def test_no_fallback_solve_where_the_first_converges(tmp_path, stopping_model):
    calls, stops = stopping_model
    stops["quad8"] = None
    compute_point("p6_fixed_x1d0.08_x1h0.001_x2d0_x2h0_td1_th1", tmp_path / "c.parquet",
                  PRESSURES, {}, fallback=FALLBACK)
    frame, _ = read_curve(tmp_path / "c.parquet")
    assert len(calls) == 1 and frame["converged"].all() and not frame["mesh_fallback"].any()


def test_in_the_load_tail_a_stop_is_kept_without_a_fallback_solve(stopping_model):
    """A ray that stops at or beyond ``fallback_below_mbar`` (the tail's start) keeps
    its stop; one that stops before it still gets the fallback."""
    from skinsuction.space import solve_with_fallbacks

    calls, _ = stopping_model
    params = dict(x1d=0.001, x1h=1e-5, probe_mm=6.0, bottom="fixed")
    p = np.asarray(PRESSURES, dtype=float)
    curve, kept, _ = solve_with_fallbacks(params, p, {}, FALLBACK, fallback_below_mbar=40.0)
    assert len(calls) == 1 and kept == 0 and curve.last_converged_mbar == 40.0
    curve, kept, _ = solve_with_fallbacks(params, p, {}, FALLBACK, fallback_below_mbar=50.0)
    assert len(calls) == 3 and kept == 1 and curve.converged


def test_a_stiffening_ray_that_stops_in_the_tail_still_gets_the_fallback(stopping_model):
    from skinsuction.space import compute_ray

    calls, _ = stopping_model
    compute_ray("p6_fixed_x1d0.001_x1h1e-05_x2d0.01_x2h0_td1_th1", PRESSURES, {}, FALLBACK,
                fallback_below_mbar=40.0)
    assert len(calls) == 2
    compute_ray("p6_fixed_x1d0.001_x1h1e-05_x2d0_x2h0_td1_th1", PRESSURES, {}, FALLBACK,
                fallback_below_mbar=40.0)
    assert len(calls) == 3


def test_splice_keeps_the_first_solve_and_joins_the_fallback_continuously(monkeypatch):
    from skinsuction.space import solve_with_fallbacks

    def simulate(skin, probe=6.0, pressures_mbar=None, mesh=None, iteration_budget=None, **kw):
        params = {k: stand_in_params(skin, probe)[k] for k in ("probe_mm", "x1d", "x1h")}
        if mesh.get("element") == "quad9":  # a stiffer (locking) element that converges
            c = stand_in_curve(params, pressures_mbar)
            return dataclasses.replace(c, deflection_mm=0.99 * c.deflection_mm)
        return stand_in_curve(params, pressures_mbar, 40.0)

    fake = types.ModuleType("skinsuction.model")
    fake.Curve, fake.simulate, fake.ParameterError = StandInCurve, simulate, ParameterError
    fake.Skin = Skin
    monkeypatch.setitem(sys.modules, "skinsuction.model", fake)
    p = np.asarray(PRESSURES)
    params = dict(x1d=0.01, x1h=1e-4, probe_mm=6.0)
    exact = stand_in_curve(params, p).deflection_mm
    whole, kept, _ = solve_with_fallbacks(params, p, {}, FALLBACK)
    spliced, kept_s, _ = solve_with_fallbacks(params, p, {}, FALLBACK, splice=True)
    assert kept == kept_s == 1 and spliced.converged
    np.testing.assert_allclose(whole.deflection_mm, 0.99 * exact)  # the fallback throughout
    below = p <= 40.0
    np.testing.assert_array_equal(spliced.deflection_mm[below], exact[below])  # first solve
    np.testing.assert_allclose(spliced.deflection_mm[~below], exact[~below], rtol=1e-12)
    assert spliced.info["spliced_at_mbar"] == 40.0
    assert spliced.info["splice_factor"] == pytest.approx(1 / 0.99)


# ------------------------------------------------------------------- provenance
def test_source_hash_changes_with_content(tmp_path):
    (tmp_path / "model").mkdir()
    (tmp_path / "model" / "a.py").write_text("x = 1\n")
    (tmp_path / "model" / "__pycache__").mkdir()
    (tmp_path / "model" / "__pycache__" / "a.pyc").write_bytes(b"junk")
    h1 = provenance.source_hash("model", root=tmp_path)
    (tmp_path / "model" / "__pycache__" / "a.pyc").write_bytes(b"other junk")
    assert provenance.source_hash("model", root=tmp_path) == h1
    (tmp_path / "model" / "a.py").write_text("x = 2\n")
    assert provenance.source_hash("model", root=tmp_path) != h1
    with pytest.raises(FileNotFoundError):
        provenance.source_hash("nothing", root=tmp_path)


def test_provenance_record_is_json(tmp_path):
    rec = provenance.collect(config={"a": np.float64(1.5), "b": (1, 2)}, extra=np.arange(2))
    assert json.loads(json.dumps(rec))["config"] == {"a": 1.5, "b": [1, 2]}
    assert rec["extra"] == [0, 1]
    assert provenance.git_info(tmp_path) == {"commit": None, "dirty": None, "root": None}


def test_flat_public_api():
    import skinsuction

    assert skinsuction.read_space is read_space and skinsuction.expand_axis is expand_axis
    assert skinsuction.SimulatedSpace is SimulatedSpace
    assert skinsuction.provenance is provenance
    assert {"simulate", "Curve", "read_space", "plot_fig3"} <= set(dir(skinsuction))
    with pytest.raises(AttributeError):
        skinsuction.no_such_name


def test_parameters_the_model_refuses_fail_the_job_loudly(tmp_path):
    # refinement 1.5 passed an older schema; every FE job then "succeeded" with no curve
    from skinsuction.space import solve_with_fallbacks

    with pytest.raises(ParameterError, match="refinement above 1 must be a whole number"):
        solve_with_fallbacks(dict(x1d=0.05, x1h=1e-3, probe_mm=6.0, bottom="fixed"),
                             [0.0, 10.0], {"refinement": 1.5}, None, label="p6 test")
