"""The default scale-free space shipped with the package (``skinsuction/data/scale_free``).

* which space a command reads: the workflow's build under the working directory,
  else the shipped one; an explicit path always wins;
* the shipped files agree with their PROVENANCE.json, are package data and are
  not hidden by .gitignore;
* a seeded random sample of its neo-Hookean 2 mm rays, solved afresh with
  ``compute_ray``, gives its deflections to 1e-6: if the FE code changes, this
  fails until the shipped space is rebuilt and shipped again
  (``snakemake --cores 2 scale_free_space && snakemake --cores 2 ship_scale_free_space``);
* ``skinsuction identify`` runs with no build of the workflow and names the space;
* the ray-by-ray comparison of the workflow's ``check_shipped_space`` rule, and the
  sampled one of ``check_shipped_sample`` (the study reading the shipped space).
"""

import fnmatch
import hashlib
import json
import re
import shutil
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from skinsuction.errors import InputError
from skinsuction.space import (
    BASELINE,
    PROVENANCE_FILE,
    SHIPPED_SPACE_DIR,
    WORKFLOW_SPACE_DIR,
    Cause,
    RaySpec,
    ShippedSpaceMismatch,
    check_shipped_sample,
    check_shipped_space,
    compare_ray_spaces,
    compute_bundle,
    compute_ray,
    default_space_dir,
    knife_edge_rays,
    load_space,
    rays_of,
    read_ray_space,
    resolve_space,
    sample_bundles,
    shipped_provenance,
    verify_shipped_files,
)

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "data" / "example_measured.csv"
NEO = f"{BASELINE}.parquet"

#: Seed of the sample of rays re-solved (any seed: the point is that it is not hand-picked).
RAY_SEED = 20261125
#: Rays re-solved, their probe, and the most a ray may have cost when it was built (s).
N_RAYS, RAY_PROBE_MM, MAX_RAY_SECONDS = 3, 2.0, 6.0
#: Relative agreement of a ray solved afresh with the shipped one.
RAY_RTOL = 1e-6

@pytest.fixture(scope="module")
def provenance():
    prov = shipped_provenance()
    assert prov is not None and (SHIPPED_SPACE_DIR / NEO).is_file(), (
        f"no default space shipped in {SHIPPED_SPACE_DIR}: build and ship it "
        "(`snakemake --cores 2 ship_scale_free_space`)")
    return prov


# ----------------------------------------------------------------- resolution
def test_without_a_build_the_default_is_the_shipped_space(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert default_space_dir() == SHIPPED_SPACE_DIR
    src = resolve_space()
    assert src.source == "shipped" and src.path == SHIPPED_SPACE_DIR
    assert src.description.startswith("the default space shipped with skinsuction ")
    assert "built at commit" in src.description
    info = load_space().info
    assert info["source"] == "shipped" and info["path"] == str(SHIPPED_SPACE_DIR)
    assert info["shipped"]["git_commit"] == src.provenance["git_commit"]
    # an empty results folder is not a build
    (tmp_path / WORKFLOW_SPACE_DIR).mkdir(parents=True)
    assert default_space_dir() == SHIPPED_SPACE_DIR


def test_a_build_of_the_workflow_in_the_working_directory_wins(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    built = tmp_path / WORKFLOW_SPACE_DIR
    built.mkdir(parents=True)
    shutil.copy(SHIPPED_SPACE_DIR / NEO, built / NEO)
    assert default_space_dir() == Path(WORKFLOW_SPACE_DIR)
    info = load_space().info
    assert info["source"] == "workflow" and info["path"] == WORKFLOW_SPACE_DIR
    assert "workflow's build" in info["description"] and "shipped" not in info
    # an explicit path wins over both
    mine = tmp_path / "mine"
    mine.mkdir()
    shutil.copy(SHIPPED_SPACE_DIR / NEO, mine / NEO)
    info = load_space(mine).info
    assert info["source"] == "given" and info["path"] == str(mine)
    # ... and so does the shipped folder named explicitly, described as shipped
    assert load_space(SHIPPED_SPACE_DIR).info["source"] == "shipped"


def test_a_missing_explicit_path_keeps_its_error(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(InputError, match=r"none: simulated space not found \(build it with"):
        load_space(tmp_path / "none")


def test_help_texts_name_the_shipped_default(capsys):
    from skinsuction.cli import main

    for command in ("identify", "diagnose", "study"):
        assert main([command, "--help"]) == 0
        text = " ".join(capsys.readouterr().out.split())
        assert "shipped with skinsuction" in text, command
        assert "results/simulated_space/scale_free if the workflow has built it" in text, command


# --------------------------------------------------------------- the files
def test_shipped_files_agree_with_their_provenance(provenance):
    assert verify_shipped_files() == []
    files = provenance["files"]
    assert NEO in files and set(files) == {p.name for p in SHIPPED_SPACE_DIR.glob("*.parquet")}
    for name, rec in files.items():
        path = SHIPPED_SPACE_DIR / name
        assert hashlib.sha256(path.read_bytes()).hexdigest() == rec["sha256"], name
        assert pq.read_metadata(path).num_rows == rec["rows"], name
        space = read_ray_space(path)
        # every model was built from the one specification the provenance records
        assert space.spec == RaySpec(**provenance["ray_spec"]), name
        assert rec["rays"] == space.metadata["n_rays"], name
    neo = read_ray_space(SHIPPED_SPACE_DIR / NEO).metadata
    assert neo["git"]["commit"] == provenance["git_commit"]
    assert neo["created_utc"] == provenance["created_utc"]
    for key in ("git_commit", "created_utc", "config_section", "build_command",
                "skinsuction_version"):
        assert provenance.get(key), key
    assert not (SHIPPED_SPACE_DIR / "rays").exists()  # the bundles are not shipped


def test_shipped_files_are_package_data_and_not_ignored_by_git():
    patterns = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"][
        "package-data"]["skinsuction"]
    shipped = [p for p in SHIPPED_SPACE_DIR.iterdir() if p.is_file()]
    assert {p.name for p in shipped} >= {NEO, PROVENANCE_FILE}
    for p in shipped:
        rel = p.relative_to(ROOT / "src" / "skinsuction").as_posix()
        assert any(fnmatch.fnmatch(rel, pat) for pat in patterns), rel
    # the tests run in a checkout (CI's is one): .gitignore must not hide the files
    assert shutil.which("git") and (ROOT / ".git").exists(), "the tests run in a git checkout"
    res = subprocess.run(["git", "check-ignore", "--no-index", *map(str, shipped)], cwd=ROOT,
                         capture_output=True, text=True)
    assert res.returncode == 1 and not res.stdout, f"ignored by git: {res.stdout}"


# ------------------------------------------- the shipped rays against the FE code
def test_a_random_sample_of_shipped_rays_is_reproduced_by_the_fe_code(provenance):
    shipped = read_ray_space(SHIPPED_SPACE_DIR / NEO)
    spec = shipped.spec
    assert spec.to_dict() == RaySpec(**provenance["ray_spec"]).to_dict()
    solver = shipped.metadata["rays"]
    candidates = [r for r in rays_of(spec) if r["probe_mm"] == RAY_PROBE_MM
                  and solver[r["ray_id"]]["seconds"] <= MAX_RAY_SECONDS]
    assert len(candidates) >= N_RAYS
    rng = np.random.default_rng(RAY_SEED)
    chosen = [candidates[i] for i in sorted(rng.choice(len(candidates), N_RAYS, replace=False))]
    failures = []
    for ray in chosen:
        t0 = time.perf_counter()
        curve, _, info = compute_ray(ray["ray_id"], spec.pressures_mbar, spec.mesh,
                                     list(spec.fallback), spec.fallback_below_mbar)
        fresh = np.asarray(curve.deflection_mm, dtype=float)
        i = spec.ratio_nodes.index(ray["ratio"])
        kept = shipped.rays(RAY_PROBE_MM)[i, 0]
        finite = np.isfinite(kept)
        if not np.array_equal(np.isfinite(fresh), finite):
            failures.append(f"{ray['ray_id']}: NaN pattern differs (fresh reaches "
                            f"{info['last_converged_mbar']:g} mbar)")
            continue
        rel = np.abs(fresh[finite] - kept[finite]) / np.maximum(np.abs(kept[finite]), 1e-12)
        if rel.max() > RAY_RTOL:
            failures.append(f"{ray['ray_id']}: largest relative difference {rel.max():.3g}")
        print(f"{ray['ray_id']}: {time.perf_counter() - t0:.2f} s, largest relative "
              f"difference {rel.max():.2g}")
    assert not failures, (
        "the FE code no longer reproduces the shipped default space ("
        + "; ".join(failures) + "): rebuild and ship it: `snakemake --cores 2 scale_free_space "
        "&& snakemake --cores 2 ship_scale_free_space`")


# ------------------------------------------------------------ the command line
def test_identify_on_a_fresh_install_reads_the_shipped_space(tmp_path):
    res = subprocess.run([sys.executable, "-m", "skinsuction", "identify", str(EXAMPLE),
                          "--objective", "weighted", "--out", "out/x"],
                         cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stdout + res.stderr
    assert "space: the default space shipped with skinsuction" in res.stdout
    result = json.loads((tmp_path / "out" / "x" / "identification.json").read_text())
    space = result["space"]
    assert space["source"] == "shipped" and space["path"] == str(SHIPPED_SPACE_DIR)
    assert space["description"].startswith("the default space shipped with skinsuction")
    assert space["shipped"]["git_commit"] == shipped_provenance()["git_commit"]
    assert space["sha256"] == shipped_provenance()["files"][NEO]["sha256"]
    iv = result["intervals"]
    assert iv["X1d"]["lower"] < 0.04 < iv["X1d"]["upper"]  # the example's truth
    assert not (tmp_path / "results").exists()
    # the fitted skin it records runs through the FE model as it is: its curve is the
    # space's fitted curve to the space's accuracy (0.2 % of M, or 0.3 µm)
    sim = subprocess.run([sys.executable, "-m", "skinsuction", "simulate", "--probe", "6",
                          "--skin", "out/x/identification.json"],
                         cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert sim.returncode == 0, sim.stdout + sim.stderr
    rows = [line for line in sim.stdout.splitlines() if line and line[0].isdigit()]
    fe = np.loadtxt(rows, delimiter=",")
    fit = result["fit"]["6"]
    fitted = np.interp(fe[:, 0], fit["pressure_mbar"], fit["fitted_mm"])
    assert np.all(np.abs(fe[:, 1] - fitted) <= 2e-3 * fitted + 0.3e-3)
    assert fe[-1, 1] > 0.1  # the 6 mm dome of the example, not an empty curve


def test_diagnose_and_study_report_the_shipped_space(tmp_path, monkeypatch):
    from skinsuction.cohort import run_study
    from skinsuction.diagnose import Settings, diagnose_file
    from skinsuction.diagnose._report import report_markdown

    monkeypatch.chdir(tmp_path)
    report = diagnose_file(EXAMPLE, settings=Settings(holdout=False, repeats=1))
    assert report["input"]["space"]["source"] == "shipped"
    assert report["input"]["space_dir"] == str(SHIPPED_SPACE_DIR)
    assert "- simulated space: the default space shipped with skinsuction" in \
        report_markdown(report)
    study = tmp_path / "study"
    study.mkdir()
    shutil.copy(EXAMPLE, study / "a.csv")
    r = run_study(study, tmp_path / "out", diagnose=False, figures=False, progress=False,
                  repeats=1)
    meta = json.loads((tmp_path / "out" / "study.json").read_text())
    assert meta["space_source"] == "shipped" and meta["space"] == str(SHIPPED_SPACE_DIR)
    assert r["space"].startswith("the default space shipped with skinsuction")
    assert "the default space shipped with skinsuction" in \
        (tmp_path / "out" / "summary.md").read_text()


# ------------------------------------------- the workflow's check, ray by ray
def _copy_with_one_ray_changed(src: Path, dst: Path, factor: float) -> str:
    """Copy a space file, one deflection of one ray multiplied by ``factor``: that ray's id."""
    table = pq.read_table(src)
    df = table.to_pandas()
    k = int(np.flatnonzero(df["deflection_mm"].to_numpy() > 0)[-1])
    df.loc[k, "deflection_mm"] *= factor
    out = pa.Table.from_pandas(df, preserve_index=False)
    pq.write_table(out.replace_schema_metadata(table.schema.metadata), dst)
    space = read_ray_space(src)
    ray = next(r for r in rays_of(space.spec, space.cause)
               if r["probe_mm"] == df.loc[k, "probe_mm"] and r["ratio"] == df.loc[k, "ratio"]
               and (space.cause is None or r["coordinate"] == df.loc[k, "coordinate"]))
    return ray["ray_id"]


def test_the_check_compares_ray_by_ray_and_fails_naming_the_ray(tmp_path, provenance):
    spec = RaySpec(**provenance["ray_spec"])
    causes = {name: Cause.from_dict(d) for name, d in provenance["causes"].items()}
    built = tmp_path / "built"
    shutil.copytree(SHIPPED_SPACE_DIR, built)
    table = check_shipped_space(built, tmp_path / "ok.csv", spec, causes)
    assert (table["status"] == "equal").all() and len(table) == len(provenance["files"])
    assert (table["rays_differing"] == 0).all() and (table["max_rel_diff"] == 0).all()
    # within the tolerance: equal; beyond it: the ray is named, and the check fails
    rid = _copy_with_one_ray_changed(SHIPPED_SPACE_DIR / NEO, built / NEO, 1 + 1e-11)
    assert check_shipped_space(built, tmp_path / "ok.csv", spec, causes)["status"].eq(
        "equal").all()
    rid = _copy_with_one_ray_changed(SHIPPED_SPACE_DIR / NEO, built / NEO, 1 + 1e-6)
    with pytest.raises(ShippedSpaceMismatch, match=re.escape(rid)):
        check_shipped_space(built, tmp_path / "bad.csv", spec, causes)
    row, bad = compare_ray_spaces(read_ray_space(built / NEO), read_ray_space(SHIPPED_SPACE_DIR / NEO))
    assert list(bad) == [rid] and row["rays_differing"] == 1
    assert row["max_rel_diff"] == pytest.approx(1e-6, rel=1e-3)
    # another configuration: the table says the check does not apply, and why
    other = RaySpec(**{**provenance["ray_spec"], "load_steps": spec.load_steps + 1})
    table = check_shipped_space(built, tmp_path / "na.csv", other, causes)
    assert table["status"].tolist() == ["not_applicable"]
    assert "ray_spec.load_steps" in table["note"][0]


def test_a_knife_edge_ray_that_moved_is_reported_not_failed(tmp_path, provenance):
    """Where a fallback carries a ray, or it stops, moves with round-off: a build on
    another machine may differ there, and the check says so without failing; a ray
    the default element carries to the end must still agree."""
    spec = RaySpec(**provenance["ray_spec"])
    causes = {name: Cause.from_dict(d) for name, d in provenance["causes"].items()}
    shipped = read_ray_space(SHIPPED_SPACE_DIR / NEO)
    edge = knife_edge_rays(shipped)
    firm = [r for r in rays_of(shipped.spec) if r["ray_id"] not in edge]
    assert edge and firm  # both kinds exist in the default space
    moved = next(r for r in rays_of(shipped.spec) if r["ray_id"] in edge)
    built = tmp_path / "built"
    shutil.copytree(SHIPPED_SPACE_DIR, built)

    def change(ray, factor):
        table = pq.read_table(SHIPPED_SPACE_DIR / NEO)
        df = table.to_pandas()
        rows = (df["probe_mm"] == ray["probe_mm"]) & (df["ratio"] == ray["ratio"])
        last = int(np.flatnonzero(rows & (df["deflection_mm"] > 0))[-1])
        df.loc[last, "deflection_mm"] *= factor
        out = pa.Table.from_pandas(df, preserve_index=False)
        pq.write_table(out.replace_schema_metadata(table.schema.metadata), built / NEO)

    change(moved, 1.01)
    table = check_shipped_space(built, tmp_path / "edge.csv", spec, causes)
    row = table.set_index("model").loc["neo_hookean"]
    assert row["status"] == "knife_edge_moved" and row["knife_edge_rays"] == 1
    assert moved["ray_id"] in row["differing_rays"]
    change(firm[0], 1.01)
    with pytest.raises(ShippedSpaceMismatch, match=re.escape(firm[0]["ray_id"])):
        check_shipped_space(built, tmp_path / "firm.csv", spec, causes)


def test_the_study_on_the_shipped_space_checks_a_sample_solved_afresh(tmp_path, provenance):
    """A bundle of two cheap rays solved now with the FE code against the shipped rays:
    equal; the same bundle with one deflection moved by 1e-6: the check fails naming
    the ray; another configuration: refused, naming the key."""
    spec = RaySpec(**provenance["ray_spec"])
    causes = {name: Cause.from_dict(d) for name, d in provenance["causes"].items()}
    shipped = read_ray_space(SHIPPED_SPACE_DIR / NEO)
    solver, edge = shipped.metadata["rays"], knife_edge_rays(shipped)
    # rays the default element carries to the end (a knife-edge ray that moved is only
    # logged): most rays stop in the load tail, these few do not
    cheap = [r["ray_id"] for r in rays_of(spec) if r["ray_id"] not in edge
             and solver[r["ray_id"]]["seconds"] <= MAX_RAY_SECONDS][-2:]
    bundle = tmp_path / f"{BASELINE}__sample.parquet"
    compute_bundle(cheap, bundle, spec.pressures_mbar, spec.mesh, list(spec.fallback),
                   fallback_below_mbar=spec.fallback_below_mbar)
    table = check_shipped_sample([bundle], tmp_path / "ok.csv", spec, causes)
    assert table["model"].tolist() == [BASELINE] and table["status"].tolist() == ["equal"]
    assert table["rays_compared"].tolist() == [2]
    moved = tmp_path / f"{BASELINE}__moved.parquet"
    t = pq.read_table(bundle)
    df = t.to_pandas()
    last = int(np.flatnonzero((df["ray_id"] == cheap[1]) & (df["deflection_mm"] > 0))[-1])
    df.loc[last, "deflection_mm"] *= 1 + 1e-6
    pq.write_table(pa.Table.from_pandas(df, preserve_index=False)
                   .replace_schema_metadata(t.schema.metadata), moved)
    with pytest.raises(ShippedSpaceMismatch, match=re.escape(cheap[1])):
        check_shipped_sample([moved], tmp_path / "bad.csv", spec, causes)
    other = RaySpec(**{**provenance["ray_spec"], "load_steps": spec.load_steps + 1})
    with pytest.raises(ShippedSpaceMismatch, match="ray_spec.load_steps"):
        check_shipped_sample([bundle], tmp_path / "na.csv", other, causes)
    # the sample is seeded, not hand-picked, and the same whatever the order
    ids = [f"b{i}" for i in range(20)]
    assert sample_bundles(ids, 4, 0) == sample_bundles(ids[::-1], 4, 0) != sample_bundles(ids, 4, 1)
