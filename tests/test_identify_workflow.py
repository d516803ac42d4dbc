"""The identification study: its functions, and its rules end to end.

The spaces are filled with the analytic surrogate (skinsuction.identify._surrogate)
instead of FE runs, so the study functions run in seconds; the workflow test
puts a surrogate space and its curve files where the workflow expects them and
swaps in a surrogate stand-in for the FE model in its copy of the sources.
"""

import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from skinsuction import paper
from test_workflow import install_stand_in
from skinsuction.model import Skin
from skinsuction.identify import analytic_surrogate_space, surrogate_curve, write_surrogate_space
from skinsuction.paper import (
    StudySetup,
    alpha_threshold,
    cost_landscape,
    fe_in_the_loop,
    landscape_summary,
    make_test_curves,
    optimiser_comparison,
    single_probe_study,
    summarise_runs,
    timing_study,
)
from skinsuction.space import point_id, write_curve

ROOT = Path(__file__).resolve().parents[1]
TARGET = np.array([0.0055, 0.00041])
FAST = {"n_samples": 300, "n_best": 10, "tolerance": 1e-6, "max_iter": 200}


@pytest.fixture(scope="module")
def setup():
    spaces = {p: analytic_surrogate_space(p) for p in (2.0, 6.0)}
    p = np.arange(0.0, 101.0, 2.0)
    fe = {probe: (p, surrogate_curve(Skin.two_layer(*TARGET), probe, pressures_mbar=p)
                  .deflection_mm)
          for probe in (2.0, 6.0)}
    from skinsuction.space import evaluate

    space = {probe: (p, evaluate(s, [TARGET], p)[0]) for probe, s in spaces.items()}
    return StudySetup(spaces, {"fe": fe, "space": space}, TARGET, FAST)


# ------------------------------------------------------------ study functions
def test_make_test_curves_has_both_variants(tmp_path):
    from skinsuction.identify import PAPER_PRESSURE_MBAR, PAPER_X1D, PAPER_X1H

    space = tmp_path / "s.parquet"
    write_surrogate_space(space, PAPER_X1D, PAPER_X1H, PAPER_PRESSURE_MBAR)
    fe = []
    for probe in (2.0, 6.0):
        params = {"probe_mm": probe, "bottom": "fixed", "x1d": 0.0055, "x1h": 0.00041}
        c = surrogate_curve(Skin.two_layer(0.0055, 0.00041), probe,
                            pressures_mbar=PAPER_PRESSURE_MBAR)
        fe.append(write_curve(c, params, tmp_path / f"{point_id(params)}.parquet"))
    table = make_test_curves(space, fe, tmp_path / "t.csv", target=TARGET)
    assert set(table["source"]) == {"fe", "space"} and set(table["probe_mm"]) == {2.0, 6.0}
    assert len(table) == 4 * 51
    curves = paper.read_test_curves(tmp_path / "t.csv")
    for probe in (2.0, 6.0):
        (pf, mf), (ps, ms) = curves["fe"][probe], curves["space"][probe]
        assert np.array_equal(pf, ps)
        # the surrogate is far from a cubic in X1d at the low end of the grid
        # (0.001 -> 0.010): interpolated at X1d = 0.0055 it is not the direct curve
        assert np.abs(ms[1:] / mf[1:] - 1).max() > 1e-3
    with pytest.raises(ValueError, match="not at the test point"):
        make_test_curves(space, fe, target=(0.006, 0.00041))


def test_single_probe_study_and_summary(setup):
    runs = single_probe_study(setup, repeats=4, seed=0)
    assert len(runs) == 2 * 2 * 4
    assert set(runs["objective"]) == {"single_6mm", "single_2mm"}
    again = single_probe_study(setup, repeats=4, seed=0)
    pd.testing.assert_frame_equal(runs.drop(columns="seconds"), again.drop(columns="seconds"))
    s = summarise_runs(runs, TARGET, ("source", "objective")).set_index(["source", "objective"])
    # a curve inside the interpolated space: the 6 mm probe identifies both moduli
    assert s.loc[("space", "single_6mm"), "success_fraction"] == 1.0
    assert abs(s.loc[("space", "single_6mm"), "x1h_error_mean_pct"]) < 0.1
    for col in ("x1d_error_mean_pct", "x1h_error_max_pct", "iterations_median", "E_median"):
        assert np.isfinite(s[col]).all()


def test_summary_errors_are_relative_to_the_truth():
    runs = pd.DataFrame({"source": "fe", "objective": "x", "x1d": [0.011, 0.011],
                         "x1h": [0.0004, 0.0006]})
    s = summarise_runs(runs, (0.01, 0.0005)).iloc[0]
    assert s["x1d_error_mean_pct"] == pytest.approx(10.0)
    assert s["x1h_error_mean_pct"] == pytest.approx(0.0, abs=1e-9)
    assert s["x1h_error_max_pct"] == pytest.approx(20.0)
    assert s["success_fraction"] == 0.0
    assert summarise_runs(runs, (0.011, 0.0004), success_tolerance=0.6).iloc[0][
        "success_fraction"] == 1.0


def test_alpha_threshold():
    summary = pd.DataFrame({"source": "fe", "alpha": [0.0, 0.25, 0.5, 0.75, 1.0],
                            "success_fraction": [1.0, 1.0, 0.97, 0.5, 0.0],
                            "x1h_error_median_pct": [0.1, 0.0, 0.2, 5.0, 70.0]})
    t = alpha_threshold(summary).iloc[0]
    assert t["last_alpha_ok_from_0"] == 0.5 and t["first_alpha_failing"] == 0.75
    assert t["alphas_all_runs_succeed"] == "0 0.25"


def test_landscape_shows_that_2mm_hardly_sees_the_hypodermis(setup):
    land = cost_landscape(setup, source="space", points=41)
    assert set(land["objective"]) == {"single_2mm", "single_6mm", "weighted", "ratio"}
    s = landscape_summary(land, TARGET).set_index("objective")
    sens = s["x1h_to_x1d_sensitivity"]
    assert sens["single_2mm"] < sens["single_6mm"] / 3, sens
    assert s.loc["single_6mm", "E_at_target"] < 1e-6  # the curve is in the space
    assert (s["fraction_not_usable"] == 0).all()


def test_timing_table_has_the_paper_numbers(setup):
    runs, table = timing_study(setup, repeats=3, sources=["space"])
    assert list(table["objective"]) == ["single_6mm", "single_2mm", "weighted", "ratio"]
    t = table.set_index("objective")
    assert (t.loc["ratio", "paper_iterations"], t.loc["ratio", "paper_seconds"]) == (10, 1.2)
    assert (t.loc["weighted", "paper_iterations"], t.loc["weighted", "paper_seconds"]) == (20, 3.8)
    assert (table["ms_median"] > 0).all() and (table["iterations_median"] >= 2).all()
    assert len(runs) == 4 * 3


def fake_fe(calls):
    def simulate(skin, probe, pressures_mbar, mesh):
        calls.append((skin.get("dermis.X1"), skin.get("hypodermis.X1")))
        return surrogate_curve(skin, probe, pressures_mbar=pressures_mbar)
    return simulate


def test_fe_in_the_loop_finds_the_truth_and_counts_solves():
    calls = []
    r = fe_in_the_loop(target=TARGET, bounds=([0.001, 1e-5], [0.091, 2.01e-3]), max_fe_solves=80,
                       simulate=fake_fe(calls), seed=0)
    assert r["success"] and np.allclose(r["estimate"], TARGET, rtol=1e-3)
    assert r["fe_solves"] == len(calls) - 1 == len(r["history"])  # -1: the target curve
    json.dumps(r)
    capped = fe_in_the_loop(target=TARGET, bounds=([0.001, 1e-5], [0.091, 2.01e-3]), max_fe_solves=3,
                            simulate=fake_fe([]), seed=0)
    assert capped["fe_solves"] == 3 and "cap of 3" in capped["message"]


def test_optimiser_comparison_table(setup):
    loop = fe_in_the_loop(target=TARGET, bounds=([0.001, 1e-5], [0.091, 2.01e-3]), max_fe_solves=40,
                          simulate=fake_fe([]), seed=0)
    runs, table = optimiser_comparison(setup, sources=["space"], runs=2,
                                       least_squares_starts=2, de_runs=1, fe_loop=loop)
    assert list(table["method"]) == ["window_focusing", "least_squares_1_start",
                                     "least_squares_2_starts", "differential_evolution",
                                     "fe_in_the_loop"]
    wf = table.iloc[0]
    assert wf["success_truth"] == 1.0 and wf["success_minimum"] == 1.0
    assert np.allclose([wf["x1d_minimum"], wf["x1h_minimum"]], TARGET, rtol=1e-6)
    assert table.iloc[-1]["fe_solves"] == loop["fe_solves"] > 0
    assert len(runs) == 2 + 2 + 2 + 1


# ------------------------------------------------------------ workflow end to end
PARTS = ("Snakefile", "workflow", "config", "src", "data")  # data: the shipped example
X1D = [0.001, 0.019, 0.037, 0.055, 0.073, 0.091]
X1H = [1.0e-5, 4.1e-4, 8.1e-4, 1.21e-3, 1.61e-3, 2.01e-3]
STAND_IN = '''"""Stand-in for the FE model (workflow tests only): the analytic surrogate."""
from types import SimpleNamespace as Curve  # noqa: F401

# the real value types (kept by install_stand_in): every package reads skins
from ._curve import ParameterError  # noqa: F401
from ._prony import Prony  # noqa: F401
from ._skin import Layer, Probe, Ramp, Skin  # noqa: F401


def simulate(*args, **kwargs):  # read when called: identify imports space, space this
    from skinsuction.identify import surrogate_curve

    return surrogate_curve(*args, **kwargs)
'''
CONFIG = {
    "spaces": {"tiny": {"probes_mm": [2, 6], "x1d": X1D, "x1h": X1H}},
    "pressures_mbar": {"start": 0, "stop": 100, "step": 10},
    "mesh": {"refinement": 0.25},
    "figure3": {"probes_mm": [6], "bottom": ["fixed"], "x1d": X1D[1], "x1h": [X1H[0]]},
    "identification": {
        "space": "tiny",
        "target": {"x1d": 0.0055, "x1h": 0.00041},
        "repeats": 3,
        "window_focusing": {"n_samples": 300, "n_best": 10},
        "figure4b": {"points": 15},
        "figure7": {"alphas": [0, 0.5, 1]},
        "comparison": {"runs": 2, "least_squares_starts": 2, "differential_evolution_runs": 1},
        "fe_in_the_loop": {"max_fe_solves": 12},
    },
}
TARGETS = [
    "results/figures/fig4_single_probe.png", "results/figures/fig4b_cost_landscape.pdf",
    "results/figures/fig7_alpha.png", "results/figures/fig8_ratio.png",
    "results/tables/fig4_single_probe.csv", "results/tables/fig4b_cost_landscape.csv",
    "results/tables/fig7_alpha.csv", "results/tables/fig7_alpha_threshold.csv",
    "results/tables/fig8_ratio.csv", "results/tables/timing.csv", "results/tables/timing.md",
    "results/tables/optimiser_comparison.csv", "results/tables/optimiser_comparison.md",
]


def snakemake(cwd, *args):
    res = subprocess.run([sys.executable, "-m", "snakemake", *args], cwd=cwd,
                         capture_output=True, text=True, timeout=600)
    out = res.stdout + res.stderr
    assert res.returncode == 0, out
    return out


def job_counts(out):
    if "Nothing to be done" in out:
        return {}
    counts = {}
    for line in out.split("Job stats:", 1)[1].splitlines()[3:]:
        parts = line.split()
        if len(parts) != 2 or parts[0] == "total":
            break
        counts[parts[0]] = int(parts[1])
    return counts


@pytest.fixture(scope="module")
def workflow_run(tmp_path_factory):
    wd = tmp_path_factory.mktemp("idwf")
    for part in PARTS:
        src = ROOT / part
        if src.is_dir():
            shutil.copytree(src, wd / part, ignore=shutil.ignore_patterns("__pycache__"))
        else:
            shutil.copy(src, wd / part)
    install_stand_in(wd, STAND_IN)
    (wd / "config" / "tiny.yaml").write_text(yaml.safe_dump(CONFIG))
    # the space and its curve files as the workflow would have made them
    write_surrogate_space(wd / "results" / "simulated_space" / "tiny.parquet", X1D, X1H,
                          np.arange(0.0, 101.0, 10.0), curves_dir=wd / "results" / "curves",
                          name="tiny")
    args = ["--configfile", "config/tiny.yaml", "--replace-workflow-config"]
    out = snakemake(wd, "--cores", "2", *args)
    return wd, args, out


def test_workflow_builds_every_identification_output(workflow_run):
    wd, args, out = workflow_run
    counts = job_counts(out)
    assert "simulate_row" not in counts and "assemble_space" not in counts
    assert counts["simulate_test_curve"] == 2 and counts["identification_runs"] == 3
    for f in TARGETS:
        assert (wd / f).stat().st_size > 0, f
    assert not list(wd.rglob(".*.tmp*")), "temporary files left behind"
    for name in ("single_probe_runs", "alpha_sweep_runs", "ratio_runs", "timing",
                 "fe_in_the_loop", "optimiser_comparison"):
        assert list((wd / "results" / "benchmarks" / "identification").glob(f"{name}*.tsv"))
    logs = wd / "logs"
    assert (logs / "identification" / "single_probe_runs.log").stat().st_size > 0


def test_workflow_tables(workflow_run):
    wd = workflow_run[0]
    t4 = pd.read_csv(wd / "results/tables/fig4_single_probe.csv")
    assert set(zip(t4["source"], t4["objective"])) == {
        (s, o) for s in ("fe", "space") for o in ("single_6mm", "single_2mm")}
    assert (t4["runs"] == 3).all()
    t7 = pd.read_csv(wd / "results/tables/fig7_alpha.csv")
    assert sorted(t7["alpha"].unique()) == [0.0, 0.5, 1.0] and len(t7) == 6
    timing = pd.read_csv(wd / "results/tables/timing.csv")
    assert len(timing) == 8 and "paper_seconds" in timing
    assert "| objective |" in (wd / "results/tables/timing.md").read_text()
    cmp_ = pd.read_csv(wd / "results/tables/optimiser_comparison.csv")
    assert cmp_["method"].iloc[-1] == "fe_in_the_loop" and cmp_["fe_solves"].iloc[-1] <= 12
    loop = json.loads((wd / "results/identification/fe_in_the_loop.json").read_text())
    assert loop["pressures_mbar"] == [float(p) for p in range(0, 101, 10)]
    curves = pd.read_csv(wd / "results/identification/test_curves.csv")
    fe6 = curves[(curves["source"] == "fe") & (curves["probe_mm"] == 6)]
    expected = surrogate_curve(Skin.two_layer(0.0055, 0.00041), 6.0,
                               pressures_mbar=fe6["pressure_mbar"]).deflection_mm
    np.testing.assert_allclose(fe6["deflection_mm"], expected, rtol=1e-12)


def test_workflow_reruns_follow_code_changes(workflow_run):
    wd, args, _ = workflow_run
    assert "Nothing to be done" in snakemake(wd, "-n", *args)
    objectives = wd / "src" / "skinsuction" / "identify" / "_objectives.py"
    original = objectives.read_text()
    objectives.write_text(original + "\n# changed\n")
    try:
        counts = job_counts(snakemake(wd, "-n", *args))
    finally:
        objectives.write_text(original)
    assert counts.get("identification_runs") == 3 and counts.get("timing_table") == 1
    assert counts.get("fe_in_the_loop") == 1 and counts.get("fig8_ratio") == 1
    assert "simulate_row" not in counts and "simulate_test_curve" not in counts
    assert "fig3_boundary_conditions" not in counts
    fig7 = wd / "src" / "skinsuction" / "figures" / "fig7.py"
    original = fig7.read_text()
    fig7.write_text(original + "\n# changed\n")
    try:
        counts = job_counts(snakemake(wd, "-n", *args))
    finally:
        fig7.write_text(original)
    assert counts.get("fig7_alpha") == 1
    assert "identification_runs" not in counts and "fe_in_the_loop" not in counts


# ------------------------------------------- NaN policy of the interpolation
def test_shifted_stencils_keep_the_space_usable_next_to_a_failed_corner():
    """One non-converged corner node (as X1d = 0.001, X1h = 1e-5 MPa of the FE space):
    "strict" loses every cell whose centred stencil holds it; "shift" only the cell
    that no NaN-free stencil contains, and stays exact for cubic data."""
    from skinsuction.space import GriddedSpace, SpaceInterpolant

    x1d = np.linspace(0.001, 0.091, 11)
    x1h = np.linspace(1e-5, 2.01e-3, 11)
    p = np.array([0.0, 50.0, 100.0])
    m = (x1d[:, None, None] ** 3 + 7 * x1h[None, :, None] ** 2) * (1 + p)  # cubic x quadratic
    m[0, 0, 1:] = np.nan  # the corner fails above 0 mbar
    space = GriddedSpace(x1d, x1h, p, m, 6.0)
    strict, shift = SpaceInterpolant(space, "strict"), SpaceInterpolant(space)
    near = np.array([[0.0055, 0.0004], [0.015, 0.0003], [0.0055, 0.00041]])
    exact = (near[:, :1] ** 3 + 7 * near[:, 1:] ** 2) * (1 + p)
    assert np.isnan(strict(near[:2])[:, 1:]).all()  # where the node is NaN
    np.testing.assert_allclose(shift(near), exact, rtol=1e-10)
    corner_cell = [[0.005, 1e-4]]  # between the failed node and its neighbours
    assert np.isnan(shift(corner_cell)[0, 1:]).all()
    # exact at every converged node, NaN nowhere else than in the corner cell
    xd, xh = np.meshgrid(np.linspace(0.001, 0.091, 61), np.linspace(1e-5, 2.01e-3, 61),
                         indexing="ij")
    cand = np.column_stack([xd.ravel(), xh.ravel()])
    values = shift(cand)
    in_corner = (cand[:, 0] < x1d[1]) & (cand[:, 1] < x1h[1])
    assert np.isfinite(values[~in_corner]).all()
    np.testing.assert_allclose(values[~in_corner],
                               ((cand[:, :1] ** 3 + 7 * cand[:, 1:] ** 2) * (1 + p))[~in_corner],
                               rtol=1e-9)
    with pytest.raises(ValueError, match="nan_policy"):
        SpaceInterpolant(space, "ignore")
