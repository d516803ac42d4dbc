"""Configuration check, grid points as wildcards, code hashes and target lists."""

import os
import re
import sys
from pathlib import Path

from snakemake.exceptions import WorkflowError
from snakemake.utils import min_version, validate

min_version("9.0")


# The workflow runs (and hashes, see code_hash) the package sources next to it,
# not another installed copy: put src/ first on the path of this process and of
# the script jobs it starts (they inherit the environment).
SRC = Path(workflow.basedir) / "src"
sys.path.insert(0, str(SRC))
os.environ.update(
    PYTHONPATH=os.pathsep.join(p for p in (str(SRC), os.environ.get("PYTHONPATH")) if p)
)

from skinsuction.config import key_error, read_config  # noqa: E402
from skinsuction.errors import InputError  # noqa: E402
from skinsuction.provenance import source_hash  # noqa: E402
from skinsuction.space import (  # noqa: E402
    POINT_ID_PATTERN, ROW_ID_PATTERN, expand_axis, grid_points, point_id, row_id,
)


# ---------------------------------------------------------------- configuration
def _config_error(key, err):
    return WorkflowError(f"Invalid configuration value for '{key}': {err}")


# the default config is read here, after a syntax check that names the line (Snakemake's
# own message names neither file nor line); a --configfile is read by Snakemake first:
# `skinsuction check-config FILE` (or `snakemake --verbose`) names its line
try:
    read_config(Path(workflow.basedir) / "config" / "config.yaml")
except InputError as _err:
    raise WorkflowError(str(_err))


# A file that says `whole_config: true` is the whole configuration: the default is not
# read under it. Snakemake does not pass --replace-workflow-config on to cluster jobs, so
# without this a cluster job would merge the file over the default and build another DAG
# than the main process (other bundle names: "KeyError: <bundle>" in the job).
if not config.get("whole_config", False):

    configfile: "config/config.yaml"


onstart:
    # the executor is known only now, before any job is submitted
    if (
        workflow.config_settings.replace_workflow_config
        and not config.get("whole_config", False)
        and workflow.non_local_exec
    ):
        raise WorkflowError(
            "--replace-workflow-config is not passed on to cluster jobs by Snakemake, which "
            "would merge your config file over config/config.yaml and plan other jobs: "
            "add `whole_config: true` to the file instead"
        )


try:
    validate(config, schema="../schemas/config.schema.yaml")
except WorkflowError as err:
    # name the offending key in the first line, e.g. 'mesh.refinement'
    _cause = err.__cause__ or err.__context__
    if hasattr(_cause, "absolute_path") and hasattr(_cause, "message"):
        raise _config_error(*key_error(_cause)) from err
    raise


try:
    PRESSURES = expand_axis(config["pressures_mbar"])
except ValueError as err:
    raise _config_error("pressures_mbar", err)
if PRESSURES[0] != 0 or PRESSURES != sorted(PRESSURES):
    raise _config_error("pressures_mbar", f"must be ascending from 0, got {PRESSURES}")

# grid points (as point ids) of every simulated space and of Figure 3
SPACE_POINTS = {}
for _name, _spec in config["spaces"].items():
    try:
        SPACE_POINTS[_name] = [point_id(p) for p in grid_points(_spec)]
    except ValueError as err:
        raise _config_error(f"spaces.{_name}", err)

try:
    FIG3_POINTS = [
        point_id(p) for p in grid_points(config["figure3"], ignore=("pressure_mbar",))
    ]
except ValueError as err:
    raise _config_error("figure3", err)
FIG3_PRESSURE = config["figure3"].get("pressure_mbar", PRESSURES[-1])
if FIG3_PRESSURE not in PRESSURES:
    raise _config_error(
        "figure3.pressure_mbar", f"{FIG3_PRESSURE} is not among pressures_mbar"
    )

ALL_POINTS = sorted(set(FIG3_POINTS).union(*SPACE_POINTS.values()))
# one FE job per row of the grids (a probe, bottom, X1d and layers; every X1h of every
# space and Figure 3 there): 28 jobs of the default config, not 320 (a point is 0.6 s
# of FE, a job of its own 2 s more of start-up and bookkeeping)
ROWS = {}
for _p in ALL_POINTS:
    ROWS.setdefault(row_id(_p), []).append(_p)


wildcard_constraints:
    point=POINT_ID_PATTERN,
    row=ROW_ID_PATTERN,
    space="|".join(map(re.escape, SPACE_POINTS)),


# ------------------------------------------------------------------- code hashes
def code_hash(*parts):
    """Hash of package sources (relative to src/skinsuction), used as a rule param.

    Snakemake does not track imported modules; a param that changes with the
    code makes a changed module rerun exactly the rules that depend on it.
    """
    try:
        return source_hash(*parts, root=SRC / "skinsuction")
    except FileNotFoundError:  # e.g. no model yet: the DAG is still valid, jobs fail on import
        return "missing"


#: The code of an FE job: the model, and the solve and storage of a point or a ray
#: (not the whole space package: an interpolation change must not rerun 650 solves).
FE_CODE = ("model", "space/_solve.py", "space/_storage.py", "_files.py", "provenance.py")
FE_RAY_CODE = (*FE_CODE, "space/_ray_solve.py", "space/_rays.py", "space/_causes.py", "space/_grid.py")
#: The code under every reader of a simulated space.
SPACE_CODE = ("space", "_files.py", "errors.py", "provenance.py")


def study_files(path):
    """Every file of a study folder (or the long CSV itself): inputs of its rule."""
    p = Path(path)
    if p.is_dir():
        return sorted(str(f) for f in p.rglob("*") if f.is_file() and not f.name.startswith("."))
    return [str(p)]


# ------------------------------------------------------------------ input lists
def curve_files(points):
    """The row files (rule simulate_row) that hold these grid points."""
    return sorted({f"results/curves/{row_id(p)}.parquet" for p in points})


def space_curves(wildcards):
    """Curve files of the grid points of one simulated space."""
    return curve_files(SPACE_POINTS[wildcards.space])


def fig3_curves(wildcards):
    """Curve files of the grid points of Figure 3."""
    return curve_files(FIG3_POINTS)


def final_outputs():
    """Everything `rule all` builds."""
    return [
        *expand("results/simulated_space/{space}.parquet", space=SPACE_POINTS),
        *expand("results/tables/{space}_convergence.csv", space=SPACE_POINTS),
        "results/figures/fig3_boundary_conditions.png",
        "results/figures/fig3_boundary_conditions.pdf",
        "results/tables/fig3_boundary_conditions.csv",
    ]


# ------------------------------------- the default scale-free space shipped with the package
#: its folder in the sources next to the workflow (skinsuction.space.SHIPPED_SPACE_DIR there)
SF_SHIPPED = SRC / "skinsuction" / "data" / "scale_free"


def shipped_space_files(wildcards=None):
    """The shipped space's files (model files and PROVENANCE.json), as far as they exist."""
    if not SF_SHIPPED.is_dir():
        return []
    return sorted(
        str(p)
        for p in SF_SHIPPED.iterdir()
        if p.suffix == ".parquet" or p.name == "PROVENANCE.json"
    )


def pair_space_files(wildcards=None):
    """The pair spaces a ramp's diagnosis reads: the workflow's build where it made them
    (SF_PAIR_SPACES, scale_free.smk), else the shipped ones (inputs, so new pair spaces
    rerun the diagnoses)."""
    built = [p for p in globals().get("SF_PAIR_SPACES", []) if Path(p).is_file()]
    if built:
        return built
    return sorted(str(p) for p in (SF_SHIPPED / "pairs").glob("*.parquet"))


def config_file_of_space():
    """Which config/*.yaml alone gives this run's scale-free space (None: a custom one).

    Each file is validated as the workflow validates its config (the schema fills
    the defaults), then its ray specification and causes are compared with this
    run's (SF_SPEC, SF_CAUSES of scale_free.smk).
    """
    import yaml

    from skinsuction.space import RaySpec, registry_from_config

    schema = Path(workflow.basedir) / "workflow" / "schemas" / "config.schema.yaml"
    for path in sorted((Path(workflow.basedir) / "config").glob("*.yaml")):
        try:
            cfg = yaml.safe_load(path.read_text(encoding="utf-8")) or {}
            validate(cfg, schema=str(schema))
            sec = cfg.get("scale_free_space")
            if sec is None:
                continue
            spec = RaySpec.from_config(sec, cfg.get("mesh"), cfg.get("mesh_fallback"))
            same = registry_from_config(sec["causes"]) == SF_CAUSES
        except Exception:  # not a config of this workflow: not a match
            continue
        if spec == SF_SPEC and same:
            return f"config/{path.name}"
    return None


def build_command(config_file):
    """The command that builds the scale-free space of ``config_file`` (None if unknown)."""
    if config_file == "config/config.yaml":
        return "snakemake --cores 2 scale_free_space"
    if config_file:
        return (
            f"snakemake --cores 2 --configfile {config_file} "
            "--replace-workflow-config scale_free_space"
        )
    return None


def design_settings(design, which):
    """The design rule's settings: the default question ("precision"), or the same
    designs with the causes told apart ("causes")."""
    d = {k: v for k, v in design.items() if k not in ("causes", "check")}
    if which == "causes":
        causes = design.get("causes", {})
        d["skins"] = causes.get("skins", 24)
        d["question"] = {**d.get("question", {}), "tell": causes["tell"]}
    return d
