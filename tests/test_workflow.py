"""The Snakemake workflow: lint, dry runs, plumbing with a stand-in model, real run.

Each test works on a copy of the workflow (Snakefile, workflow/, config/, src/) in
a temporary folder, so that results/ and .snakemake/ of the checkout are never
touched. The workflow runs the package sources next to it (common.smk puts src/
first on the path), which lets the plumbing test swap in a stand-in FE model in
its copy only.
"""

import json
import re
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from skinsuction.space import grid_points, point_id, read_space, row_id

ROOT = Path(__file__).resolve().parents[1]
PARTS = ("Snakefile", "workflow", "config", "src", "data")  # data: the shipped example


def copy_workflow(dst: Path) -> Path:
    for part in PARTS:
        src = ROOT / part
        if src.is_dir():
            shutil.copytree(src, dst / part, ignore=shutil.ignore_patterns("__pycache__"))
        else:
            shutil.copy(src, dst / part)
    return dst


def snakemake(cwd, *args, check=True, timeout=600):
    res = subprocess.run(
        [sys.executable, "-m", "snakemake", *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=timeout,
    )
    out = res.stdout + res.stderr
    if check and res.returncode != 0:
        raise AssertionError(f"snakemake {' '.join(args)} failed ({res.returncode}):\n{out}")
    return out


def job_counts(out: str) -> dict:
    """Jobs per rule from the 'Job stats' table of a (dry) run."""
    if "Nothing to be done" in out:
        return {}
    table = out.split("Job stats:", 1)[1]
    counts = {}
    for line in table.splitlines()[3:]:
        m = re.match(r"^(\w+)\s+(\d+)$", line.strip())
        if not m or m.group(1) == "total":
            break
        counts[m.group(1)] = int(m.group(2))
    return counts


def expected_points(config: dict) -> set:
    pts = {point_id(p) for spec in config["spaces"].values() for p in grid_points(spec)}
    pts |= {point_id(p) for p in grid_points(config["figure3"], ignore=("pressure_mbar",))}
    return pts


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    return copy_workflow(tmp_path_factory.mktemp("wf"))


def test_lint_is_clean(workdir):
    out = snakemake(workdir, "--lint")
    assert "Lints for" not in out, out
    assert "Congratulations" in out, out


@pytest.mark.parametrize("name,n_space", [("config", 242), ("ci", 50)])
def test_dry_run_lists_one_fe_job_per_row_of_the_grids(workdir, name, n_space):
    out = snakemake(
        workdir, "-n", "--configfile", f"config/{name}.yaml", "--replace-workflow-config"
    )
    config = yaml.safe_load((workdir / "config" / f"{name}.yaml").read_text())
    n_fig3 = len(grid_points(config["figure3"], ignore=("pressure_mbar",)))
    counts = job_counts(out)
    points = expected_points(config)
    assert len(points) == n_space + n_fig3
    assert counts["simulate_row"] == len({row_id(p) for p in points})
    if name == "config":  # eq. 3: 2 probes x 11 X1d; Figure 3: 2 probes x 3 bottoms
        assert counts["simulate_row"] == 22 + 6
    assert counts["assemble_space"] == len(config["spaces"])
    assert counts["convergence_table"] == len(config["spaces"])
    assert counts["fig3_boundary_conditions"] == 1


def _planned_outputs(out: str) -> list:
    """The output files of every job of a dry run, sorted."""
    return sorted(re.findall(r"^\s*output: (.+)$", out, flags=re.M))


def test_ci_config_plans_the_same_jobs_merged_or_alone(workdir):
    # A cluster job re-reads the Snakefile without --replace-workflow-config (Snakemake
    # does not pass it on): its DAG must equal the main process's, or the job fails
    # with "KeyError: <bundle>" (rays_per_job came from the default only).
    alone = snakemake(workdir, "-n", "--configfile", "config/ci.yaml",
                      "--replace-workflow-config")
    merged = snakemake(workdir, "-n", "--configfile", "config/ci.yaml")
    assert _planned_outputs(alone) and _planned_outputs(alone) == _planned_outputs(merged)
    assert job_counts(alone) == job_counts(merged)


def test_a_partial_overlay_still_merges_over_the_default(workdir):
    # an overlay without whole_config keeps the default's spaces (here: the paper's)
    out = snakemake(workdir, "-n", *write_config(workdir, "overlay_only",
                                                 {"pressures_mbar": {"start": 0, "stop": 100,
                                                                     "step": 2}})[:2])
    assert job_counts(out)["simulate_row"] == 28


def test_the_confusion_with_the_dermis_given_is_one_job_a_draw(workdir):
    # a cluster runs the draws side by side; a stopped run keeps the draws it finished
    config = yaml.safe_load((workdir / "config" / "config.yaml").read_text())
    per = config["diagnosis"]["confusion_given_layers"]["per_cause"]
    truths = 1 + sum(c["keyword"] != "t_d" for c in config["scale_free_space"]["causes"].values())
    out = snakemake(workdir, "-n", "confusion_given_layers")
    counts = job_counts(out)
    assert counts["confusion_given_layers_draw"] == truths * per == 4 * per
    assert counts["confusion_given_layers"] == 1
    assert "results/diagnosis/confusion_given_layers/pre_tension_3" in out  # seed 1000 + 300000


def test_the_confusion_with_both_layers_given_draws_neither_thickness(workdir):
    overlay = {"diagnosis": {"confusion_given_layers": {"per_cause": 2,
                                                        "hypodermis_sd_mm": 0.2}}}
    out = snakemake(workdir, "-n", "confusion_given_layers",
                    *write_config(workdir, "both_given", overlay)[:2])
    assert job_counts(out)["confusion_given_layers_draw"] == 3 * 2  # none, 2 causes
    assert "confusion_given_layers/hypodermis_thickness_" not in out
    # one cause fewer: pre_tension is the 2nd cause (config order), seed 1000 + 200000
    assert "results/diagnosis/confusion_given_layers/pre_tension_201000" in out


def test_a_cause_with_t_d_nodes_of_its_own_has_a_job_a_node_and_unpacks_the_shipped_ones(
        workdir):
    config = yaml.safe_load((workdir / "config" / "config.yaml").read_text())
    causes = config["scale_free_space"]["geometry"]["causes"]
    own = causes["t_d_over_a_of"]["strain_stiffening"]
    assert set(causes["t_d_over_a"]) < set(own)
    out = snakemake(workdir, "-n",
                    "results/simulated_space/scale_free/geometry/strain_stiffening.parquet")
    # one job per (t_d/a, t_h/a) node, as pre-tension's (t_h_per_job)
    assert causes["t_h_per_job"]["strain_stiffening"] == 1
    own_th = causes.get("t_h_over_a_of", {}).get("strain_stiffening", causes["t_h_over_a"])
    assert job_counts(out)["simulate_geometry_bundle"] == len(own) * len(own_th)
    assert "strain_stiffening__td0.7354__th0.2182" in out
    out = snakemake(workdir, "-n", "logs/scale_free/geometry/unpack_strain_stiffening.json")
    assert job_counts(out) == {"unpack_geometry_space": 1}
    bad = {"scale_free_space": {"geometry": {"causes": {"t_d_over_a_of": {"dermis_thickness":
                                                                          own}}}}}
    out = snakemake(workdir, "-n", *write_config(workdir, "bad_own", bad)[:2], check=False)
    assert "t_d_over_a_of: 'dermis_thickness' is not in causes.names" in out


def test_a_cause_with_t_h_nodes_of_its_own_solves_them_alone(workdir):
    # one cause's t_h/a node added before the other's (both causes have their own nodes
    # in the config; 0.072 is in neither): its jobs alone, the other cause's untouched
    causes = yaml.safe_load((workdir / "config" / "config.yaml").read_text())[
        "scale_free_space"]["geometry"]["causes"]
    assert all(0.072 not in v for v in causes["t_h_over_a_of"].values())
    th = sorted([0.072, *causes["t_h_over_a_of"]["pre_tension"]])
    overlay = {"scale_free_space": {"geometry": {"causes": {
        "t_h_over_a_of": {"pre_tension": th}}}}}
    args = write_config(workdir, "own_th", overlay)[:2]
    rays = "results/simulated_space/scale_free/geometry"
    out = snakemake(workdir, "-n", f"{rays}/pre_tension.parquet", *args)
    own = causes["t_d_over_a_of"]["pre_tension"]
    assert job_counts(out)["simulate_geometry_bundle"] == len(own) * len(th)
    assert "pre_tension__td0.7354__th0.072" in out
    out = snakemake(workdir, "-n", f"{rays}/strain_stiffening.parquet", *args)
    own_ss = causes["t_d_over_a_of"]["strain_stiffening"]
    own_ss_th = causes["t_h_over_a_of"]["strain_stiffening"]
    assert job_counts(out)["simulate_geometry_bundle"] == len(own_ss) * len(own_ss_th)
    assert "__th0.072" not in out
    bad = {"scale_free_space": {"geometry": {"causes": {"t_h_over_a_of": {"creep": th}}}}}
    out = snakemake(workdir, "-n", *write_config(workdir, "bad_own_th", bad)[:2], check=False)
    assert "t_h_over_a_of: 'creep' is not in causes.names" in out


def test_the_neo_hookean_geometry_in_jobs_of_one_t_h_node_solves_only_new_nodes(workdir):
    # a grid extended by t_h/a nodes: with one node a job, the shipped space's jobs
    # are unpacked, the new nodes' jobs alone are solved
    grid = yaml.safe_load((workdir / "config" / "config.yaml").read_text())[
        "scale_free_space"]["geometry"]
    th = sorted([0.045, *grid["t_h_over_a"]])
    overlay = {"scale_free_space": {"geometry": {"t_h_over_a": th, "causes": {
        "t_h_per_job": {"pre_tension": 1, "neo_hookean": 1}}}}}
    args = write_config(workdir, "thin", overlay)[:2]
    target = "results/simulated_space/scale_free/geometry/neo_hookean.parquet"
    out = snakemake(workdir, "-n", target, *args)
    assert job_counts(out)["simulate_geometry_bundle"] == len(grid["t_d_over_a"]) * len(th)
    assert f"rays/td{grid['t_d_over_a'][0]:g}__th0.045.parquet" in out
    out = snakemake(workdir, "-n", "logs/scale_free/geometry/unpack_neo_hookean.json", *args)
    assert job_counts(out) == {"unpack_geometry_space": 1}


def test_default_invocation_runs_the_paper_study(workdir):
    counts = job_counts(snakemake(workdir, "-n"))
    assert counts["simulate_row"] == 28
    # it reads the shipped scale-free space, checked against a sample of its rays
    config = yaml.safe_load((workdir / "config" / "config.yaml").read_text())
    assert config["scale_free_space"]["source"] == "shipped"
    assert counts["simulate_ray_bundle"] == config["scale_free_space"]["check_bundles"]
    assert counts["check_shipped_sample"] == 1
    assert "assemble_scale_free_space" not in counts and "check_shipped_space" not in counts


def test_the_space_is_built_with_its_overlay_or_its_target(workdir):
    built = job_counts(snakemake(workdir, "-n", "--configfile", "config/build_space.yaml"))
    target = job_counts(snakemake(workdir, "-n", "scale_free_space"))
    for counts in (built, target):
        assert counts["simulate_ray_bundle"] == 92
        assert counts["assemble_scale_free_space"] == 5 and counts["check_shipped_space"] == 1
    assert "check_shipped_sample" not in built


def test_the_shipped_space_under_another_configuration_is_refused(workdir):
    # the shipped space holds the default's rays only: another load range must build
    overlay = {"scale_free_space": {"load": {"max": 60000}}}
    out = snakemake(workdir, "-n", *write_config(workdir, "other_load", overlay)[:2],
                    check=False)
    assert "scale_free_space.source" in out and "ray_spec.load_max" in out, out[-2000:]
    assert "set it to build" in out


# ------------------------------------------------- plumbing with a stand-in model
STAND_IN_MODEL = '''
"""Stand-in for the FE model, for workflow plumbing tests only (not the real model)."""
import numpy as np

from dataclasses import dataclass, field


@dataclass(frozen=True)
class Curve:  # the fields of skinsuction.model.Curve
    pressure_mbar: np.ndarray
    deflection_mm: np.ndarray
    converged: bool
    last_converged_mbar: float
    reason: str = ""
    newton_iterations: int = 0
    dofs: int = 0
    seconds: float = 0.0
    info: dict = field(default_factory=dict)


# the real value types (kept by install_stand_in): every package reads skins
from ._curve import ParameterError  # noqa: F401
from ._prony import Prony  # noqa: F401
from ._skin import Layer, Probe, Ramp, Skin  # noqa: F401


def simulate(skin, probe=6.0, pressures_mbar=None, mesh=None):
    x1d, x1h, bottom, probe_mm = skin.get("dermis.X1"), skin.get("hypodermis.X1"), skin.bottom, probe
    p = np.arange(0, 101, 2.0) if pressures_mbar is None else np.asarray(pressures_mbar, float)
    soft = {"fixed": 1.0, "axial": 1.05, "free": 1.3}[bottom]
    m = soft * 0.02 * probe_mm * np.sqrt(p) / (x1d * 40 + x1h * 400) ** 0.3
    info = {"stand_in": True, "mesh": mesh}
    if x1h >= 0.05:  # pretend the solver gives up at 20 mbar
        return Curve(p, np.where(p <= 20, m, np.nan), False, 20.0, "too many cut-backs",
                     25, 100, 0.01, info)
    return Curve(p, m, True, float(p[-1]), "", 2 * len(p), 100, 0.01, info)
'''


#: The modules of the real model a stand-in keeps: its value types, no FE.
VALUE_MODULES = ("_curve.py", "_prony.py", "_skin.py")


def install_stand_in(workdir, source=None):
    """Replace the FE model of a workflow copy by a stand-in, keeping its value types."""
    model = workdir / "src" / "skinsuction" / "model"
    for f in model.iterdir():
        if f.is_dir():
            shutil.rmtree(f)
        elif f.name not in VALUE_MODULES:
            f.unlink()
    (model / "__init__.py").write_text(STAND_IN_MODEL if source is None else source)
    return model

TINY = {
    "spaces": {
        "tiny": {"probes_mm": [6], "x1d": [0.05], "x1h": [1.0e-4, 0.1]},
    },
    "pressures_mbar": {"start": 0, "stop": 100, "step": 20},
    "mesh": {"refinement": 0.25},
    "figure3": {
        "probes_mm": [6],
        "bottom": ["fixed", "free"],
        "x1d": 0.05,
        "x1h": [1.0e-4, 0.1],
        "pressure_mbar": 100,
    },
}


def write_config(workdir, name, config):
    path = workdir / "config" / f"{name}.yaml"
    path.write_text(yaml.safe_dump(config))
    return ["--configfile", f"config/{name}.yaml", "--replace-workflow-config"]


@pytest.fixture(scope="module")
def stand_in_run(tmp_path_factory):
    workdir = copy_workflow(tmp_path_factory.mktemp("plumbing"))
    install_stand_in(workdir)
    args = write_config(workdir, "tiny", TINY)
    out = snakemake(workdir, "--cores", "2", *args)
    return workdir, args, out


def test_stand_in_run_builds_everything(stand_in_run):
    workdir, args, out = stand_in_run
    counts = job_counts(out)
    assert counts["simulate_row"] == 2  # the space's row, shared with Figure 3, + its free row
    for f in (
        "results/simulated_space/tiny.parquet",
        "results/tables/tiny_convergence.csv",
        "results/figures/fig3_boundary_conditions.png",
        "results/figures/fig3_boundary_conditions.pdf",
        "results/tables/fig3_boundary_conditions.csv",
    ):
        assert (workdir / f).stat().st_size > 0, f
    assert len(list((workdir / "results" / "curves").glob("*.parquet"))) == 2
    assert not list(workdir.rglob(".*.tmp*")), "temporary files left behind"
    for log in (workdir / "logs" / "simulate").glob("*.log"):
        assert "converged=" in log.read_text()
    assert len(list((workdir / "results" / "benchmarks" / "simulate").glob("*.tsv"))) == 2
    assert "Nothing to be done" in snakemake(workdir, "-n", *args)


def test_stand_in_database_keeps_failed_points_and_provenance(stand_in_run):
    workdir, args, out = stand_in_run
    s = read_space(workdir / "results" / "simulated_space" / "tiny.parquet")
    assert s.frame["point_id"].nunique() == 2 and len(s.frame) == 2 * 6
    failed = s.points[~s.points["converged"]]
    assert failed["x1h"].tolist() == [0.1]
    assert (failed["reason"] == "too many cut-backs").all()
    x1d, x1h, p, m = s.grid(6.0)
    assert m.shape == (1, 2, 6) and np.isnan(m[0, 1, p > 20]).all() and np.isfinite(m[0, 0]).all()
    meta = s.metadata
    assert meta["space"] == "tiny" and meta["config"]["spaces"].keys() == {"tiny"}
    assert meta["mesh"]["refinement"] == 0.25 and meta["mesh"]["element"] == "quad8"
    assert meta["versions"]["felupe"] and meta["git"].keys() >= {"commit", "dirty"}
    info = next(iter(meta["points"].values()))
    assert info["curve_info"]["stand_in"] is True
    assert info["curve_info"]["mesh"]["refinement"] == 0.25
    assert len(info["source_hash"]["model"]) == 16
    conv = pd.read_csv(workdir / "results" / "tables" / "tiny_convergence.csv")
    assert conv[["probe_mm", "n_points", "n_converged"]].values.tolist() == [[6, 2, 1]]


def test_stand_in_fig3_table(stand_in_run):
    workdir, args, out = stand_in_run
    t = pd.read_csv(workdir / "results" / "tables" / "fig3_boundary_conditions.csv")
    assert len(t) == 4 and set(t["bottom"]) == {"fixed", "free"}
    assert (t.loc[t["x1h"] == 0.1, "reached"] == False).all()  # noqa: E712
    ok = t[t["reached"]]
    free = ok[ok["bottom"] == "free"].set_index(["probe_mm", "x1h"])["deflection_mm"]
    fixed = ok[ok["bottom"] == "fixed"].set_index(["probe_mm", "x1h"])["deflection_mm"]
    assert (free > fixed).all()


def test_reruns_follow_config_and_code_changes(stand_in_run):
    workdir, args, out = stand_in_run
    # a mesh setting reruns every FE job (and what depends on them)
    finer = json.loads(json.dumps(TINY))
    finer["mesh"]["refinement"] = 0.5
    counts = job_counts(snakemake(workdir, "-n", *write_config(workdir, "finer", finer)))
    assert counts["simulate_row"] == 2 and counts["fig3_boundary_conditions"] == 1
    # a new grid value reruns only its row; Figure 3 reads that row too
    wider = json.loads(json.dumps(TINY))
    wider["spaces"]["tiny"]["x1h"].append(1.0e-3)
    counts = job_counts(snakemake(workdir, "-n", *write_config(workdir, "wider", wider)))
    assert counts == {"simulate_row": 1, "assemble_space": 1, "convergence_table": 1,
                      "fig3_boundary_conditions": 1, "all": 1}
    # the model code reruns all FE jobs; the figure code only the figure
    init = workdir / "src" / "skinsuction" / "model" / "__init__.py"
    init.write_text(init.read_text() + "\n# changed\n")
    assert job_counts(snakemake(workdir, "-n", *args))["simulate_row"] == 2
    init.write_text(STAND_IN_MODEL)
    assert "Nothing to be done" in snakemake(workdir, "-n", *args)
    style = workdir / "src" / "skinsuction" / "figures" / "_style.py"
    style.write_text(style.read_text() + "\n# changed\n")
    assert job_counts(snakemake(workdir, "-n", *args)) == {"fig3_boundary_conditions": 1, "all": 1}


# ------------------------------------------ the scale-free space, stand-in model
TINY_SCALE_FREE = {
    **TINY,
    "scale_free_space": {
        "probes_mm": [6],
        "ratio": [0.001, 0.01, 0.1],
        "load": {"max": 200, "steps": 5, "refine": 2},  # + loads 10, 20 (the onset)
        "x1d_mpa": {"min": 0.1, "max": 10.0},
        "x1d_ref": 0.5,  # X1h = 0.05 MPa at the last ratio: the stand-in stops at 20 mbar
        "causes": {"strain_stiffening": {"keyword": "x2d", "symbol": "X2d", "unit": "MPa",
                                         "modulus": True, "neutral": 0.0, "scale": "log1p",
                                         "nodes": [0.0, 3.0, 10.0]}},
    },
}


def test_stand_in_scale_free_space_bundles_assembly_and_coverage(tmp_path):
    from skinsuction.space import read_ray_spaces

    workdir = copy_workflow(tmp_path)
    install_stand_in(workdir)
    args = write_config(workdir, "tiny_sf", TINY_SCALE_FREE)
    counts = job_counts(snakemake(workdir, "--cores", "2", *args, "scale_free_space"))
    # one job per (model, probe, ratio); the neutral rays once, in the neo-Hookean bundles
    assert counts["simulate_ray_bundle"] == 2 * 3
    assert counts["assemble_scale_free_space"] == 2 and counts["scale_free_coverage"] == 1
    spaces = read_ray_spaces(workdir / "results" / "simulated_space" / "scale_free")
    assert set(spaces) == {"neo_hookean", "strain_stiffening"}
    assert spaces["strain_stiffening"].rays(6.0).shape == (3, 3, 8)
    assert np.isfinite(spaces["neo_hookean"].rays(6.0)[:, 0, :3]).all()  # 0 and the onset
    cov = pd.read_csv(workdir / "results" / "tables" / "scale_free_coverage.csv")
    short = cov[~cov["complete"]]
    # the stand-in stops at 20 mbar for X1h >= 0.05 MPa: p/X1d = 40 at the last ratio
    assert set(short["ratio"]) == {0.1} and (short["load_reached"] == 40.0).all()
    assert (short["reason"] == "too many cut-backs").all()
    assert (workdir / "results" / "figures" / "scale_free_coverage.png").stat().st_size > 0
    assert "Nothing to be done" in snakemake(workdir, "-n", *args, "scale_free_space")
    # a new cause node reruns the bundles of that cause only
    more = json.loads(json.dumps(TINY_SCALE_FREE))
    more["scale_free_space"]["causes"]["strain_stiffening"]["nodes"].append(30.0)
    counts = job_counts(snakemake(workdir, "-n", *write_config(workdir, "more", more),
                                  "scale_free_space"))
    assert counts["simulate_ray_bundle"] == 3


# --------------------------------------------------------- end to end, real model
REAL_TINY = {
    "spaces": {"tiny": {"probes_mm": [6], "x1d": [0.05], "x1h": [1.0e-3]}},
    "pressures_mbar": {"start": 0, "stop": 100, "step": 10},
    "mesh": {"refinement": 0.25},
    "figure3": {
        "probes_mm": [6],
        "bottom": ["fixed", "free"],
        "x1d": 0.05,
        "x1h": [1.0e-3],
        "pressure_mbar": 100,
    },
}


@pytest.mark.slow
def test_end_to_end_with_the_real_model(tmp_path):
    """Two FE curves with the real model (skinsuction.model.simulate), the whole workflow.

    Fails, on purpose, while skinsuction.model does not provide simulate().
    """
    import skinsuction
    from skinsuction.model import Curve, simulate  # fails loudly until the model exists

    assert skinsuction.simulate is simulate and skinsuction.Curve is Curve

    workdir = copy_workflow(tmp_path)
    args = write_config(workdir, "tiny", REAL_TINY)
    out = snakemake(workdir, "--cores", "2", *args, timeout=1800)
    assert job_counts(out)["simulate_row"] == 2  # fixed and free
    s = read_space(workdir / "results" / "simulated_space" / "tiny.parquet")
    pts = s.points
    assert len(pts) == 1 and pts["converged"].all(), pts[["point_id", "reason"]]
    x1d, x1h, p, m = s.grid(6.0)
    assert m.shape == (1, 1, 11) and m[0, 0, 0] == pytest.approx(0.0, abs=1e-9)
    assert np.all(np.diff(m[0, 0]) > 0), "deflection must grow with suction"
    t = pd.read_csv(workdir / "results" / "tables" / "fig3_boundary_conditions.csv")
    assert t["reached"].all() and (t["deflection_mm"] > 0).all()
    free = t.loc[t["bottom"] == "free", "deflection_mm"].item()
    fixed = t.loc[t["bottom"] == "fixed", "deflection_mm"].item()
    assert free >= fixed * (1 - 1e-6)  # the free interface is the softest (paper, 3.1)


def test_a_cluster_run_refuses_replace_workflow_config_without_whole_config(tmp_path):
    # the option would not reach the cluster jobs: refused before any job is submitted
    workdir = copy_workflow(tmp_path)
    full = yaml.safe_load((workdir / "config" / "config.yaml").read_text())
    args = write_config(workdir, "mine", full)
    out = snakemake(workdir, "--executor", "slurm", "--jobs", "1", *args, check=False,
                    timeout=300)
    assert "add `whole_config: true` to the file" in out, out
    assert "has been submitted" not in out, out
