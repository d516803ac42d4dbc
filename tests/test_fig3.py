"""Figure 3: table from curves, plot, files."""


import numpy as np
import pandas as pd
import pytest

from skinsuction.figures import fig3
from skinsuction.figures.fig3 import build_fig3, plot_fig3, table_fig3
from skinsuction.space import curve_frame, grid_points, point_id, write_curve

PRESSURES = np.arange(0, 101, 20.0)
SPEC = {"probes_mm": [6, 2], "bottom": ["fixed", "axial", "free"], "x1d": 0.08, "x1h": {"logspace": [-5, -1, 3]}}


class Curve:
    def __init__(self, params, fail_above=None):
        soft = {"fixed": 1.0, "axial": 1.05, "free": 1.3}[params["bottom"]]
        m = soft * params["probe_mm"] * 0.01 * np.sqrt(PRESSURES) / (1 + 100 * params["x1h"])
        self.pressure_mbar = PRESSURES
        self.converged = fail_above is None
        self.last_converged_mbar = 100.0 if fail_above is None else fail_above
        self.deflection_mm = m if fail_above is None else np.where(PRESSURES <= fail_above, m, np.nan)
        self.reason = "" if fail_above is None else "diverged"
        self.newton_iterations, self.dofs, self.seconds, self.info = 10, 100, 0.1, {}


def frame(failing=()):
    rows = []
    for params in grid_points(SPEC):
        fail = failing.get(point_id(params)) if failing else None
        rows.append(curve_frame(Curve(params, fail), params))
    return pd.concat(rows, ignore_index=True)


def test_table_reads_m_at_the_maximal_pressure():
    pts = grid_points(SPEC)
    stopped = point_id(pts[-1])  # 2 mm, free, X1h = 0.1
    never = point_id(pts[-2])
    t = table_fig3(frame({stopped: 40.0, never: float("nan")}))
    assert list(t.columns) == list(fig3.TABLE_COLUMNS)
    assert len(t) == 18 and t["probe_mm"].iloc[0] == 6.0
    assert (t["pressure_mbar"] == 100).all()
    row = t.set_index("point_id").loc[stopped]
    assert not row["reached"] and np.isnan(row["deflection_mm"])
    assert row["deflection_last_mm"] == pytest.approx(1.3 * 2 * 0.01 * np.sqrt(40) / 11)
    assert np.isnan(t.set_index("point_id").loc[never, "deflection_last_mm"])
    ok = t[t["reached"]]
    assert np.allclose(ok["deflection_mm"], ok["deflection_last_mm"])
    t60 = table_fig3(frame(), pressure_mbar=60)
    assert (t60["pressure_mbar"] == 60).all() and t60["reached"].all()
    with pytest.raises(ValueError, match="no pressure"):
        table_fig3(frame(), pressure_mbar=50)


def test_plot_has_two_apertures_and_marks_unconverged_points():
    pts = grid_points(SPEC)
    fig = plot_fig3(table_fig3(frame({point_id(pts[-1]): 40.0})))
    titles = [ax.get_title() for ax in fig.axes]
    assert titles[0].startswith("(a) 6 mm") and titles[1].startswith("(b) 2 mm")
    assert all(ax.get_xscale() == "log" for ax in fig.axes)
    assert fig.axes[0].get_xlim() == pytest.approx((1e-5, 1e-1))
    legends = [t.get_text() for leg in fig.legends for t in leg.get_texts()]
    assert any("not converged up to 100 mbar (1 point(s))" in t for t in legends)
    hollow = [
        line for line in fig.axes[1].get_lines() if line.get_markerfacecolor() == "none"
    ]
    assert len(hollow) == 1 and hollow[0].get_xdata()[0] == 0.1
    clean = plot_fig3(table_fig3(frame()))
    assert len(clean.legends) == 1


def test_build_writes_files_reproducibly(tmp_path):
    paths = []
    for params in grid_points({**SPEC, "probes_mm": [6]}):
        path = tmp_path / "curves" / f"{point_id(params)}.parquet"
        write_curve(Curve(params), params, path)
        paths.append(path)
    out = {k: tmp_path / f"fig3.{k}" for k in ("png", "pdf", "csv")}
    table = build_fig3(paths, out["png"], out["pdf"], out["csv"], pressure_mbar=100)
    assert len(table) == 9
    assert pd.read_csv(out["csv"])["reached"].all()
    assert out["png"].read_bytes()[:4] == b"\x89PNG" and out["pdf"].read_bytes()[:4] == b"%PDF"
    first = out["pdf"].read_bytes()
    build_fig3(paths, out["png"], out["pdf"], out["csv"], pressure_mbar=100)
    assert out["pdf"].read_bytes() == first
    assert sorted(p.name for p in tmp_path.iterdir()) == ["curves", "fig3.csv", "fig3.pdf", "fig3.png"]


