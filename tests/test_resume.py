"""Kill the workflow mid-run (SIGTERM, SIGKILL) and resume: nothing lost, nothing corrupt.

The workflow runs with a slow stand-in FE model (0.4 s a curve; the plumbing of
test_workflow) on 12 grid points and Figure 3 (6 rows of the grids, a job each), so that FE jobs are running when
it is killed.  The resumed run (`--rerun-incomplete`, after `--unlock` for a
SIGKILL) must give the database of an uninterrupted run, must not recompute a
curve that was finished, and no partially written Parquet may ever be readable.
A truncated curve file is reported by name at assembly.
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time

import pandas as pd
import pyarrow.parquet as pq
import pytest

from test_workflow import STAND_IN_MODEL, copy_workflow, install_stand_in, snakemake, write_config

SLOW_MODEL = STAND_IN_MODEL.replace(
    "    info = {\"stand_in\": True, \"mesh\": mesh}",
    "    import time\n    time.sleep(0.4)\n    info = {\"stand_in\": True, \"mesh\": mesh}")

CONFIG = {
    "spaces": {"grid": {"probes_mm": [6], "x1d": [0.02, 0.04, 0.06, 0.08],
                        "x1h": [1.0e-4, 1.0e-3, 0.01]}},
    "pressures_mbar": {"start": 0, "stop": 100, "step": 20},
    "mesh": {"refinement": 0.25},
    "figure3": {"probes_mm": [6], "bottom": ["fixed", "free"], "x1d": 0.05,
                "x1h": [1.0e-4, 0.1], "pressure_mbar": 100},
}
DB = "results/simulated_space/grid.parquet"


def _workdir(tmp_path, name):
    (tmp_path / name).mkdir()
    wd = copy_workflow(tmp_path / name)
    install_stand_in(wd, SLOW_MODEL)
    return wd, write_config(wd, "resume", CONFIG)


def _readable_curves(wd):
    """Every curve file must read completely (atomic writes; the temporary files being
    written are hidden, named ``.<name>.<pid>.tmp.parquet``, and never read)."""
    out = {}
    for f in (wd / "results" / "curves").glob("*.parquet"):
        if f.name.startswith("."):
            continue
        pq.read_table(f)  # raises on a partial file
        out[f.name] = f.stat().st_mtime_ns
    return out


def _database(wd):
    return pd.read_parquet(wd / DB).sort_values(["point_id", "pressure_mbar"]).reset_index(
        drop=True)[["point_id", "pressure_mbar", "deflection_mm", "converged"]]


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    wd, args = _workdir(tmp_path_factory.mktemp("ref"), "ref")
    snakemake(wd, "--cores", "2", *args)
    return _database(wd)


@pytest.mark.parametrize("sig, when", [(signal.SIGTERM, "fe"), (signal.SIGKILL, "assembly")])
def test_killed_run_resumes_to_the_uninterrupted_database(sig, when, reference, tmp_path):
    wd, args = _workdir(tmp_path, "run")
    proc = subprocess.Popen([sys.executable, "-m", "snakemake", "--cores", "2", *args],
                            cwd=wd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True)
    deadline = time.monotonic() + 300
    seen = {}
    try:
        while time.monotonic() < deadline and proc.poll() is None:
            seen.update(_readable_curves(wd))  # at any time: no partial file is readable
            # 3 of 6 rows (4 of the grid, 2 of Figure 3) written: the first 2 are registered
            # as finished (a file just written may still be deleted as incomplete)
            fe_done = len(seen) >= 3
            assembling = (wd / "logs" / "space" / "grid.log").exists()
            if (when == "fe" and fe_done) or (when == "assembly" and assembling):
                break
            time.sleep(0.05)
        assert proc.poll() is None, "the run ended before it could be killed"
        os.killpg(proc.pid, sig)
        proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    before = _readable_curves(wd)
    assert before and not (wd / DB).exists() or when == "assembly"
    if sig == signal.SIGKILL:
        snakemake(wd, "--unlock", *args)
    snakemake(wd, "--cores", "2", "--rerun-incomplete", *args)
    after = _readable_curves(wd)
    recomputed = [f for f, t in before.items() if after[f] != t]
    # only the jobs running at the kill (at most --cores of them) may be redone
    assert len(recomputed) <= 2, recomputed
    pd.testing.assert_frame_equal(_database(wd), reference)
    assert not list(wd.rglob(".*.tmp*")), "temporary files left behind"
    assert "Nothing to be done" in snakemake(wd, "-n", *args)


def test_a_truncated_curve_file_is_reported_by_name(tmp_path):
    wd, args = _workdir(tmp_path, "trunc")
    snakemake(wd, "--cores", "2", *args)
    victim = wd / "results" / "curves" / "p6_fixed_x1d0.04_x2d0_x2h0_td1_th1.parquet"  # a row
    data = victim.read_bytes()
    victim.write_bytes(data[: len(data) // 2])
    (wd / DB).unlink()
    out = snakemake(wd, "--cores", "2", *args, check=False)
    assert f"{victim.name}: unreadable curve file" in out and "delete it and rerun" in out
    victim.unlink()
    snakemake(wd, "--cores", "2", *args)
    assert len(pd.read_parquet(wd / DB)["point_id"].unique()) == 12
