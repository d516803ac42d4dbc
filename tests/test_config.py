"""The study configurations and their schema."""

import copy
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import yaml
from snakemake.exceptions import WorkflowError
from snakemake.utils import validate

from skinsuction.model import MeshSettings
from skinsuction.space import expand_axis, grid_points

ROOT = Path(__file__).resolve().parents[1]
SCHEMA = ROOT / "workflow" / "schemas" / "config.schema.yaml"
CONFIGS = {name: ROOT / "config" / f"{name}.yaml" for name in ("config", "ci")}


def load(name):
    return yaml.safe_load(CONFIGS[name].read_text())


@pytest.mark.parametrize("name", sorted(CONFIGS))
def test_configs_validate(name):
    config = load(name)
    validate(config, str(SCHEMA))
    assert config["mesh"]["element"] == "quad8"
    # every fallback is a valid model setting (the schema lists only some keys), but
    # for the solver's own: its Newton budget and stall rule
    solver_keys = ("iterations_per_step", "stall_after")
    for fallback in config["mesh_fallback"] or []:
        MeshSettings.from_dict({k: v for k, v in fallback.items() if k not in solver_keys})
    for spec in config["spaces"].values():
        assert grid_points(spec)
    assert expand_axis(config["pressures_mbar"])[0] == 0


def test_paper_config_is_the_paper_study():
    config = load("config")
    paper = grid_points(config["spaces"]["paper"])
    assert len(paper) == 2 * 11 * 11
    assert {p["probe_mm"] for p in paper} == {2.0, 6.0}
    assert {p["bottom"] for p in paper} == {"fixed"}
    assert expand_axis(config["pressures_mbar"]) == [float(p) for p in range(0, 101, 2)]
    fig3 = grid_points(config["figure3"], ignore=("pressure_mbar",))
    assert len(fig3) == 2 * 3 * 13
    assert {p["x1d"] for p in fig3} == {0.08}
    x1h = sorted({p["x1h"] for p in fig3})
    assert x1h[0] == 1e-5 and x1h[-1] == 0.1


def test_ci_config_is_coarse():
    config = load("ci")
    n = sum(len(grid_points(s)) for s in config["spaces"].values())
    assert n <= 2 * 5 * 5  # 5 x 5: identification needs a few cubic cells (issue: identification)
    assert config["mesh"]["refinement"] <= 0.5
    assert 3 <= len(expand_axis(config["figure3"]["x1h"])) <= 4


def test_defaults_are_filled_in():
    config = {
        "spaces": {"s": {"probes_mm": [6], "x1d": 0.01, "x1h": [1e-4]}},
        "pressures_mbar": {"start": 0, "stop": 100, "step": 2},
        "figure3": {"probes_mm": [6], "x1d": 0.08, "x1h": {"logspace": [-5, -1, 3]}},
    }
    validate(config, str(SCHEMA))
    # the schema's defaults are the model's own defaults
    assert config["mesh"] == MeshSettings().to_dict()
    assert config["spaces"]["s"]["bottom"] == ["fixed"]
    assert config["spaces"]["s"]["x2d"] == [0.0] and config["spaces"]["s"]["t_h"] == [1.0]
    assert config["figure3"]["bottom"] == ["fixed", "axial", "free"]


def test_spaces_with_second_order_and_thickness_axes_are_admitted():
    config = load("config")
    config["spaces"]["x2"] = {
        "probes_mm": [6],
        "x1d": {"start": 0.01, "stop": 0.05, "step": 0.02},
        "x1h": {"logspace": [-5, -3, 3]},
        "x2d": [-0.01, 0.0, 0.05],
        "x2h": {"start": 0, "stop": 0.002, "step": 0.001},
        "t_d": [0.8, 1.2],
        "t_h": {"start": 1, "stop": 5, "step": 2},
        "bottom": "axial",
    }
    validate(config, str(SCHEMA))
    assert len(grid_points(config["spaces"]["x2"])) == 3 * 3 * 3 * 3 * 2 * 3


BAD = [
    ("mesh.refinement", -1, "refinement"),
    ("mesh.refinement", 9, "refinement"),
    ("mesh.element", "quad4", "element"),
    ("mesh.edge_size", 0.0, "edge_size"),
    ("mesh.quadrature", "gauss", "quadrature"),
    ("mesh.outer_radius_factor", 0.5, "outer_radius_factor"),
    ("mesh.smoothing", 1, "smoothing"),
    ("spaces.paper.probes_mm", [0], "probes_mm"),
    ("spaces.paper.probes_mm", [], "probes_mm"),
    ("spaces.paper.x1d", {"start": 0.0, "stop": 0.1, "step": 0.01}, "x1d"),
    ("spaces.paper.x1h", {"start": 1e-5, "stop": 1e-3, "step": -1e-4}, "x1h"),
    ("spaces.paper.bottom", ["glued"], "bottom"),
    ("spaces.paper.t_h", [0.0], "t_h"),
    ("spaces.paper.thickness", [1.0], "thickness"),
    ("spaces.bad/name", {"probes_mm": [6], "x1d": 0.01, "x1h": 0.001}, "bad/name"),
    ("pressures_mbar", {"start": 10, "stop": 100, "step": 2}, "pressures_mbar"),
    ("figure3.x1h", {"logspace": [-5, -1, 0]}, "x1h"),
    ("figure3.pressure_mbar", -5, "pressure_mbar"),
    ("identification", {"n": 1000}, "identification"),
    ("mesh_fallback", {"element": "quad4"}, "mesh_fallback"),
    ("mesh_fallback", [{"wall_penalty": 0}], "mesh_fallback"),
    ("mesh_fallback", [], "mesh_fallback"),
    ("mesh_fallback", {"smoothing": 1}, "mesh_fallback"),
    ("mesh.refinement", 1.5, "refinement"),  # above 1 the mesh subdivides: whole numbers
    ("studies.synthetic.level", 1.0, "level"),
    ("studies.synthetic.repeats", 0, "repeats"),
]


def _set(config, dotted, value):
    *parents, last = dotted.split(".")
    node = config
    for key in parents:
        node = node[key]
    node[last] = value


@pytest.mark.parametrize("dotted,value,key", BAD, ids=[f"{d}={v}" for d, v, _ in BAD])
def test_invalid_values_are_refused_naming_the_key(dotted, value, key):
    config = copy.deepcopy(load("config"))
    _set(config, dotted, value)
    with pytest.raises(WorkflowError, match=re.escape(key)):
        validate(config, str(SCHEMA))


def test_workflow_stops_on_invalid_config_naming_the_key(tmp_path):
    for part in ("Snakefile", "workflow", "config", "src"):
        src = ROOT / part
        if src.is_dir():
            shutil.copytree(src, tmp_path / part, ignore=shutil.ignore_patterns("__pycache__"))
        else:
            shutil.copy(src, tmp_path / part)
    config = load("config")
    config["mesh"]["refinement"] = -1
    (tmp_path / "bad.yaml").write_text(yaml.safe_dump(config))
    res = subprocess.run(
        [sys.executable, "-m", "snakemake", "-n", "--configfile", "bad.yaml"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert res.returncode != 0
    assert "Invalid configuration value for 'mesh.refinement'" in res.stdout + res.stderr


def _dry_run(cwd, *args):
    res = subprocess.run([sys.executable, "-m", "snakemake", "-n", *args], cwd=cwd,
                         capture_output=True, text=True, timeout=300)
    return res.returncode, res.stdout + res.stderr


def test_a_target_outside_its_space_and_a_yaml_syntax_error_are_named(tmp_path):
    from test_workflow import copy_workflow

    copy_workflow(tmp_path)
    config = load("config")
    config["identification"]["target"]["x1d"] = 5.0
    (tmp_path / "bad.yaml").write_text(yaml.safe_dump(config))
    code, out = _dry_run(tmp_path, "--configfile", "bad.yaml")
    assert code != 0 and "'identification.target.x1d': 5 MPa is outside the space" in out
    text = (tmp_path / "config" / "config.yaml").read_text().splitlines()
    line = next(i for i, s in enumerate(text) if s.startswith("  refinement:"))
    text[line] = "  refinement: [1"
    (tmp_path / "config" / "config.yaml").write_text("\n".join(text) + "\n")
    code, out = _dry_run(tmp_path)
    assert code != 0 and f"config.yaml, line {line + 2}" in out and "not valid YAML" in out


def _check_config(cwd, *args):
    res = subprocess.run([sys.executable, "-m", "skinsuction", "check-config", *args], cwd=cwd,
                         capture_output=True, text=True, timeout=120)
    return res.returncode, res.stdout + res.stderr


def test_check_config_names_the_line_of_a_users_configfile(tmp_path):
    # Snakemake reads a --configfile before the workflow and names no line: the
    # command does, and names a bad key as the workflow does
    bad = tmp_path / "mine.yaml"
    bad.write_text("mesh:\n  refinement: 1\nspaces:\n  paper: {x1d: [0.1, 0.2\n  other: 1\n")
    code, out = _check_config(ROOT, str(bad))
    assert code == 2, out
    assert re.search(r"mine\.yaml, line 5, column \d+: not valid YAML", out), out
    assert "Traceback" not in out
    code, dry = _dry_run(ROOT, "--configfile", str(bad))
    assert code != 0 and "not valid JSON or YAML" in dry  # Snakemake's own, unlocated

    bad.write_text("mesh:\n  refinement: 1.5\n")
    code, out = _check_config(ROOT, str(bad))
    assert code == 2 and "'mesh.refinement'" in out and "over config/config.yaml" in out, out
    code, out = _check_config(ROOT, str(bad), "--no-base")
    assert code == 2 and "'<top level>'" in out and "required" in out, out
    bad.write_text("- a list\n")
    code, out = _check_config(ROOT, str(bad))
    assert code == 2 and "a mapping of keys" in out, out

    for args in (["config/ci.yaml"], ["config/ci.yaml", "--no-base"], ["config/config.yaml"]):
        code, out = _check_config(ROOT, *args)
        assert code == 0 and "a valid configuration" in out, (args, out)
        # ci.yaml is a whole configuration: checked alone, as the workflow reads it
        assert ("merged over" in out) == (args == ["config/config.yaml"]), (args, out)

    bad.write_text("whole_config: true\nmesh:\n  refinement: 1\n")  # whole, but no spaces
    code, out = _check_config(ROOT, str(bad))
    assert code == 2 and "required" in out and "over config/config.yaml" not in out, out


def _pins(lines):
    pins = {}
    for line in lines:
        m = re.match(r"^\s*-?\s*([A-Za-z0-9_.\-]+)==([^\s#]+)", line)
        if m:
            pins[m.group(1).lower()] = m.group(2)
    return pins


def test_environment_pins_are_exact_and_match_the_rule_environment():
    lines = (ROOT / "environment.txt").read_text().splitlines()
    reqs = [l.strip() for l in lines if l.strip() and not l.strip().startswith("#")]
    assert reqs[-1] == "-e ."
    assert all("==" in r for r in reqs[:-1]), reqs
    pins = _pins(reqs)
    for name in ("felupe", "snakemake", "snakemake-executor-plugin-slurm", "numpy", "scipy",
                 "pandas", "pyarrow", "matplotlib", "pytest", "hypothesis", "pyyaml", "jsonschema"):
        assert name in pins, name
    assert pins["felupe"] == "11.3.0" and pins["snakemake"] == "9.27.1"
    env = _pins((ROOT / "workflow" / "envs" / "skinsuction.yaml").read_text().splitlines())
    assert env and all(pins[k] == v for k, v in env.items()), env
