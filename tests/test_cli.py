"""The command line: ``skinsuction simulate`` and ``skinsuction identify``.

``simulate`` runs against a stand-in for the FE model (monkeypatched), and
``identify`` against a small simulated space filled with the analytic surrogate,
so these tests take seconds.
"""

import io
import json
import shutil
import subprocess
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from skinsuction import cli
from skinsuction.identify import analytic_surrogate_space
from skinsuction.space import evaluate
from skinsuction.identify import write_surrogate_space

ROOT = Path(__file__).resolve().parents[1]
X1D = np.linspace(0.001, 0.091, 7)
X1H = np.linspace(1e-5, 2.01e-3, 7)
P = np.arange(0.0, 101.0, 5.0)
TRUTH = (0.04, 0.0005)


def run(argv, capsys):
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


# ------------------------------------------------------------------ help
def test_help_lists_the_subcommands(capsys):
    code, out, _ = run(["--help"], capsys)
    assert code == 0 and "simulate" in out and "identify" in out


def test_simulate_help_gives_every_option_with_units(capsys):
    code, out, _ = run(["simulate", "--help"], capsys)
    assert code == 0
    text = " ".join(out.split())
    for option, unit in [("--probe", "mm"), ("--x1d", "MPa"), ("--x1h", "MPa"),
                         ("--x2d", "MPa"), ("--x2h", "MPa"), ("--td", "mm"), ("--th", "mm"),
                         ("--bottom", "fixed"), ("--refinement", "dimensionless"),
                         ("--out", "atomically")]:
        assert option in text
        help_text = text.split(option)[-1][:200]
        assert unit in help_text, (option, help_text)


def test_identify_help(capsys):
    code, out, _ = run(["identify", "--help"], capsys)
    text = " ".join(out.split())
    assert code == 0
    for word in ("--space", "--objective", "--alpha", "--repeats", "--seed", "--out", "mbar"):
        assert word in text


def test_commands_registry_is_the_parser():
    parser = cli.build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    assert set(sub.choices) == set(cli.COMMANDS) == {"simulate", "identify", "diagnose", "study",
                                                      "design", "rparams", "check-config",
                                                      "export-inp"}


# ------------------------------------------------------------------ simulate
def fake_simulate(calls, converge=True):
    def simulate(skin, probe, pressures_mbar=None, mesh=None, progress=None):
        calls.append(dict(skin=skin, probe_mm=probe, pressures_mbar=pressures_mbar, mesh=mesh))
        p = np.arange(0.0, 101.0, 2.0)
        for k in range(1, p.size):
            progress(k, p.size - 1, p[k])
        m = 0.01 * p
        last = 100.0
        if not converge:
            last = 40.0
            m = np.where(p <= last, m, np.nan)
        return SimpleNamespace(pressure_mbar=p, deflection_mm=m, converged=converge,
                               last_converged_mbar=last,
                               reason="" if converge else "no equilibrium above 41 mbar",
                               newton_iterations=7, dofs=99, seconds=0.5, info={})
    return simulate


def test_simulate_prints_the_curve_with_the_solver_note(monkeypatch, capsys):
    calls = []
    monkeypatch.setattr("skinsuction.model.simulate", fake_simulate(calls))
    code, out, err = run(["simulate", "--probe", 2, "--x1d", 0.08, "--x1h", 4.1e-4,
                          "--x2d", 0.5, "--th", 2, "--bottom", "axial", "--refinement", 0.5],
                         capsys)
    assert code == 0 and err == ""
    from skinsuction.model import Skin

    (call,) = calls
    assert call["skin"] == Skin.two_layer(0.08, 4.1e-4, x2d=0.5, t_h=2.0, bottom="axial")
    assert call["probe_mm"] == 2.0 and call["mesh"] == {"refinement": 0.5}
    np.testing.assert_array_equal(call["pressures_mbar"], np.arange(0.0, 101.0, 2.0))
    assert "# converged: true" in out and "# last_converged_mbar: 100" in out
    assert "# reason:" in out
    frame = pd.read_csv(io.StringIO(out), comment="#")
    assert list(frame.columns) == ["pressure_mbar", "deflection_mm"]
    assert len(frame) == 51 and frame["deflection_mm"].iloc[-1] == pytest.approx(1.0)


class FakeTerminal(io.StringIO):
    def isatty(self):
        return True


def test_progress_draws_a_bar_on_a_terminal_and_writes_lines_in_a_log():
    from skinsuction import Progress

    tty = FakeTerminal()
    bar = Progress(4, "simulate", "pressures", stream=tty)
    for k in range(4):
        bar.step(note=f"{25 * (k + 1)} mbar")
    assert tty.getvalue().count("\r") == 4 and tty.getvalue().endswith("\n")
    assert "simulate [##############################] 4/4" in tty.getvalue()
    assert "100 mbar" in tty.getvalue()

    log = io.StringIO()
    bar = Progress(4, "rays", "bundles", stream=log, every=3600.0)
    for _ in range(4):
        bar.step()
    # the first step and the last: nothing in between within the hour
    lines = log.getvalue().splitlines()
    assert len(lines) == 2 and "\r" not in log.getvalue()
    assert lines[0].startswith("rays: 1/4 bundles (25 %)")
    assert lines[1].startswith("rays: 4/4 bundles (100 %)")

    quiet = io.StringIO()
    bar = Progress(4, "simulate", stream=quiet, quiet_below=3600.0)
    for _ in range(4):
        bar.step()
    assert quiet.getvalue() == ""  # a quick run says nothing

    stopped = FakeTerminal()
    bar = Progress(4, "simulate", stream=stopped)
    bar.step()
    bar.close()
    assert stopped.getvalue().endswith("\n")  # a run that stopped early ends its line


def test_simulate_reports_progress_on_a_terminal(monkeypatch, capsys):
    monkeypatch.setattr("skinsuction.model.simulate", fake_simulate([]))
    stderr = FakeTerminal()
    monkeypatch.setattr("sys.stderr", stderr)
    monkeypatch.setattr("skinsuction.commands.simulate.PROGRESS_QUIET_S", 0.0)  # the fake is instant
    code, out, _ = run(["simulate", "--probe", 6, "--x1d", 0.08, "--x1h", 4.1e-4], capsys)
    assert code == 0
    assert "simulate [" in stderr.getvalue() and "50/50" in stderr.getvalue()
    assert "100 mbar" in stderr.getvalue()


def test_simulate_stopped_early_exits_3_and_still_writes(monkeypatch, capsys, tmp_path):
    monkeypatch.setattr("skinsuction.model.simulate", fake_simulate([], converge=False))
    target = tmp_path / "sub" / "curve.csv"
    code, out, err = run(["simulate", "--probe", 6, "--x1d", 0.001, "--x1h", 1e-5,
                          "--out", target], capsys)
    assert code == 3 and out == ""
    assert "stopped at 40 mbar" in err and len(err.strip().splitlines()) == 1
    text = target.read_text()
    assert "# converged: false" in text and "# last_converged_mbar: 40" in text
    assert "# reason: no equilibrium above 41 mbar" in text
    frame = pd.read_csv(target, comment="#")
    assert frame["deflection_mm"].isna().sum() == 30  # 42 ... 100 mbar
    assert not list(target.parent.glob(".*tmp*")), "temporary file left behind"


@pytest.mark.parametrize("argv, word", [
    (["--probe", "-6", "--x1d", "0.08", "--x1h", "1e-4"], "--probe"),
    (["--probe", "6", "--x1d", "abc", "--x1h", "1e-4"], "--x1d"),
    (["--probe", "6", "--x1d", "0.08", "--x1h", "1e-4", "--bottom", "glued"], "--bottom"),
    (["--probe", "6", "--x1d", "0.08"], "--x1h"),
    (["--probe", "6"], "--skin FILE or --x1d and --x1h"),
    (["--probe", "6", "--skin", "s.yaml", "--x1d", "0.08"], "not both (--x1d)"),
    (["--probe", "6", "--x1d", "0.08", "--x1h", "1e-4", "--max-mbar", "2000"], "max_mbar"),
    (["--probe", "6", "--x1d", "0.08", "--x1h", "1e-4", "--refinement", "50"], "--refinement"),
    (["--probe", "6", "--x1d", "0.08", "--x1h", "1e-4", "--refinement", "1e-6"], "--refinement"),
    (["--probe", "6", "--x1d", "0.08", "--x1h", "1e-4", "--refinement", "1.5"], "--refinement"),
])
def test_simulate_bad_arguments_exit_2(argv, word, capsys, monkeypatch):
    monkeypatch.setattr("skinsuction.model.simulate", fake_simulate([]))
    code, out, err = run(["simulate", *argv], capsys)
    assert code == 2 and word in err and "Traceback" not in err


def test_simulate_takes_a_skin_file_with_three_layers(monkeypatch, capsys, tmp_path):
    """--skin FILE: any stack; the header records the skin, the ramp is the options'."""
    from skinsuction.model import Skin

    skin = Skin.two_layer(0.08, 4.1e-4, t_d=0.9).with_layer_on_top("superficial", 0.1, 0.02)
    path = skin.write(tmp_path / "skin.yaml")
    calls = []
    monkeypatch.setattr("skinsuction.model.simulate", fake_simulate(calls))
    code, out, err = run(["simulate", "--probe", 2, "--skin", path, "--max-mbar", 450,
                          "--step-mbar", 50, "--bottom", "free"], capsys)
    assert code == 0 and err == ""
    (call,) = calls
    assert call["skin"] == Skin(skin.layers, "free")
    assert call["pressures_mbar"].tolist() == list(range(0, 451, 50))
    header = [line for line in out.splitlines() if line.startswith("# skin: ")]
    assert Skin.from_dict(json.loads(header[0][len("# skin: "):])) == Skin(skin.layers, "free")
    assert "# x1d_mpa" not in out and "# ramp_mbar: 0 to 450 by 50" in out


def test_simulate_a_bad_skin_file_is_one_line_naming_it(capsys, tmp_path):
    path = tmp_path / "skin.yaml"
    path.write_text("layers: [{name: dermis, thickness: 1}]")
    code, out, err = run(["simulate", "--probe", 2, "--skin", path], capsys)
    assert code == 2 and err.count("\n") == 1
    assert str(path) in err and "missing ['X1']" in err


def test_simulate_a_three_layer_skin_end_to_end(capsys, tmp_path):
    """The real model through the command line: a superficial layer softens M."""
    from skinsuction.model import Skin

    skin = Skin.two_layer(0.08, 4.1e-4, t_d=0.9).with_layer_on_top("superficial", 0.1, 0.02)
    args = ["--probe", 2, "--max-mbar", 20, "--step-mbar", 10, "--refinement", 0.5]
    code, three, _ = run(["simulate", "--skin", skin.write(tmp_path / "s.yaml"), *args], capsys)
    code2, two, _ = run(["simulate", "--x1d", 0.08, "--x1h", 4.1e-4, *args], capsys)
    assert code == code2 == 0
    m3, m2 = (pd.read_csv(io.StringIO(t), comment="#")["deflection_mm"].iloc[-1]
              for t in (three, two))
    assert m3 > 1.05 * m2


def test_simulate_model_refusal_is_one_line(monkeypatch, capsys):
    def refuse(*args, **kwargs):
        raise ValueError("t_d must be positive")
    monkeypatch.setattr("skinsuction.model.simulate", refuse)
    code, out, err = run(["simulate", "--probe", 6, "--x1d", 0.08, "--x1h", 1e-4], capsys)
    assert code == 2 and err.count("\n") == 1 and "t_d must be positive" in err


# ------------------------------------------------------------------ identify
@pytest.fixture(scope="module")
def space_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("space") / "surrogate.parquet"
    write_surrogate_space(path, X1D, X1H, P)
    return path


def measured_csv(path, probes=(6.0, 2.0), truth=TRUTH, noise_um=0.0, extra=""):
    rng = np.random.default_rng(1)
    lines = ["# subject: test", "probe_mm,pressure_mbar,deflection_mm"]
    p = np.arange(0.0, 101.0, 2.0)  # not the space's pressures: interpolated in p
    for probe in probes:
        m = evaluate(analytic_surrogate_space(probe, X1D, X1H, P), [truth], p)[0]
        m = m + 1e-3 * noise_um * rng.standard_normal(p.size) * (p > 0)
        lines += [f"{probe:g},{a:g},{b:.6f}" for a, b in zip(p, m)]
    path.write_text("\n".join(lines) + "\n" + extra, encoding="utf-8")
    return path


@pytest.mark.parametrize("objective", ["single", "weighted", "ratio"])
def test_identify_writes_json_and_plot(objective, space_file, tmp_path, capsys):
    csv = measured_csv(tmp_path / "m.csv")
    out = tmp_path / "out"
    code, stdout, err = run(["identify", csv, "--space", space_file, "--objective", objective,
                             "--repeats", 4, "--seed", 3, "--out", out], capsys)
    assert code == 0, err
    assert "X1d = " in stdout
    result = json.loads((out / "identification.json").read_text())
    assert result["estimate"]["x1d_mpa"] == pytest.approx(TRUTH[0], rel=2e-3)
    assert result["estimate"]["x1h_mpa"] == pytest.approx(TRUTH[1], rel=2e-3)
    assert result["settings"]["objective"] == objective and result["settings"]["seed"] == 3
    assert result["settings"]["repeats"] == len(result["runs"]) == 4
    assert result["settings"]["window_focusing"] == {
        "n_samples": 1000, "n_best": 20, "tolerance": 1e-6, "max_iter": 200}
    assert result["input"]["sha256"] == __import__("hashlib").sha256(csv.read_bytes()).hexdigest()
    assert result["space"]["sha256"] and result["space"]["name"] == "surrogate"
    assert {"x1d_std_mpa", "x1h_relative_iqr", "x1d_range_mpa"} <= set(result["spread"])
    assert result["E"]["unit"] == ("1" if objective == "ratio" else "µm")
    assert result["iterations"]["median"] >= 2
    probes = {"single": {"6"}, "weighted": {"2", "6"}, "ratio": {"2", "6"}}[objective]
    assert set(result["fit"]) == probes
    for f in result["fit"].values():
        assert len(f["residual_um"]) == len(f["pressure_mbar"]) == 51
        assert max(abs(r) for r in f["residual_um"]) < 1.0
    assert (out / "fit.png").stat().st_size > 1000 and (out / "fit.pdf").stat().st_size > 1000


def test_identify_is_reproducible_from_the_seed(space_file, tmp_path, capsys):
    csv = measured_csv(tmp_path / "m.csv", noise_um=2.0)
    results = []
    for k in range(2):
        run(["identify", csv, "--space", space_file, "--objective", "single", "--probe", 2,
             "--repeats", 3, "--out", tmp_path / f"o{k}"], capsys)
        results.append(json.loads((tmp_path / f"o{k}" / "identification.json").read_text()))
    assert results[0]["runs"] == results[1]["runs"]
    assert results[0]["settings"]["probe_mm"] == 2.0


BAD_FILES = {
    "decimal comma": ("probe_mm,pressure_mbar,deflection_mm\n6,0,0\n6,50,0,4\n", "line 3"),
    "Pa": ("probe_mm,pressure_mbar,deflection_mm\n6,0,0\n6,5000,0.4\n6,10000,0.7\n",
           "column 'pressure_mbar'"),
    "unknown column": ("probe,pressure_mbar,deflection_mm\n6,0,0\n", "column 'probe'"),
    "not a number": ("probe_mm,pressure_mbar,deflection_mm\n6,0,0\n6,x,0.4\n",
                     "line 3, column 'pressure_mbar'"),
    "probe not in space": ("probe_mm,pressure_mbar,deflection_mm\n8,0,0\n8,50,0.4\n",
                           "column 'probe_mm'"),
    "no 6 mm curve": ("probe_mm,pressure_mbar,deflection_mm\n2,0,0\n2,50,0.04\n2,100,0.07\n",
                      "no 6 mm curve"),
    "binary": (b"\xff\xfe\x00garbage", "not UTF-8"),
}


@pytest.mark.parametrize("case", sorted(BAD_FILES))
def test_identify_bad_input_is_one_line_and_exit_2(case, space_file, tmp_path, capsys):
    content, expected = BAD_FILES[case]
    csv = tmp_path / "bad.csv"
    csv.write_bytes(content if isinstance(content, bytes) else content.encode())
    code, out, err = run(["identify", csv, "--space", space_file, "--objective", "single",
                          "--repeats", 2, "--out", tmp_path / "out"], capsys)
    assert code == 2
    assert err.startswith("skinsuction identify: error: ") and err.count("\n") == 1, err
    assert str(csv) in err and expected in err
    assert "Traceback" not in err
    assert not (tmp_path / "out" / "identification.json").exists()


def test_identify_bad_space_and_choices(space_file, tmp_path, capsys):
    csv = measured_csv(tmp_path / "m.csv", probes=(6.0,))
    for argv, expected in [
        (["--space", tmp_path / "none.parquet", "--objective", "single"], "not found"),
        (["--space", csv, "--objective", "single"], "not a simulated-space database"),
        (["--space", space_file, "--objective", "weighted"], "no 2 mm curve"),
        (["--space", space_file, "--objective", "ratio"], "no 2 mm curve"),
        (["--space", space_file, "--objective", "single", "--alpha", "1.5"], "[0, 1]"),
        (["--space", space_file, "--objective", "lsq"], "invalid choice"),
        (["--space", space_file, "--objective", "single", "--repeats", "0"], ">= 1"),
    ]:
        code, out, err = run(["identify", csv, *argv, "--out", tmp_path / "o"], capsys)
        assert code == 2 and expected in err and "Traceback" not in err, (argv, err)


def test_identify_replicates_need_curve(space_file, tmp_path, capsys):
    p = np.arange(0.0, 101.0, 10.0)
    m = evaluate(analytic_surrogate_space(6.0, X1D, X1H, P), [TRUTH], p)[0]
    rows = [f"6,{a:g},{b:.6f},{c}" for c in ("A", "B") for a, b in zip(p, m * (1 + 0.01 * (c == "B")))]
    csv = tmp_path / "rep.csv"
    csv.write_text("probe_mm,pressure_mbar,deflection_mm,curve\n" + "\n".join(rows) + "\n")
    code, out, err = run(["identify", csv, "--space", space_file, "--objective", "single",
                          "--repeats", 2, "--out", tmp_path / "o"], capsys)
    assert code == 2 and "--curve" in err and "['A', 'B']" in err
    code, out, err = run(["identify", csv, "--space", space_file, "--objective", "single",
                          "--repeats", 2, "--curve", "B", "--out", tmp_path / "o"], capsys)
    assert code == 0, err
    assert json.loads((tmp_path / "o" / "identification.json").read_text())[
        "input"]["curves"]["6"]["curve"] == "B"


def test_internal_errors_are_one_line_unless_debug(monkeypatch, capsys, tmp_path):
    def boom(*args, **kwargs):
        raise RuntimeError("kaputt")
    monkeypatch.setattr("skinsuction.model.simulate", boom)
    code, out, err = run(["simulate", "--probe", 6, "--x1d", 0.08, "--x1h", 1e-4], capsys)
    assert code == 1 and "internal error: RuntimeError: kaputt" in err and err.count("\n") == 1
    with pytest.raises(RuntimeError):
        cli.main(["--debug", "simulate", "--probe", "6", "--x1d", "0.08", "--x1h", "1e-4"])


@pytest.mark.skipif(shutil.which("skinsuction") is None, reason="entry point not installed")
def test_entry_point_in_a_real_process(space_file, tmp_path):
    """The installed command: exit codes and no traceback on bad input."""
    res = subprocess.run(["skinsuction", "--version"], capture_output=True, text=True)
    assert res.returncode == 0 and res.stdout.startswith("skinsuction ")
    bad = tmp_path / "bad.csv"
    bad.write_text("probe_mm;pressure_mbar;deflection_mm\n6;0;0\n")
    res = subprocess.run(["skinsuction", "identify", str(bad), "--space", str(space_file),
                          "--objective", "single", "--out", str(tmp_path / "o")],
                         capture_output=True, text=True)
    assert res.returncode == 2 and "Traceback" not in res.stderr
    assert res.stderr.strip() == (f"skinsuction identify: error: {bad}, line 1: columns must be "
                                  "separated by ',', the header uses ';'")


def test_example_file_is_labelled_synthetic_and_loads():
    from skinsuction.measured import load_measured

    data = load_measured(ROOT / "data" / "example_measured.csv", available_probes=[2, 6],
                         pressure_range_mbar=(0, 100))
    assert data.probes == (2.0, 6.0)
    assert "SYNTHETIC" in data.comments[0] and data.metadata["subject"] == "synthetic"
    assert float(data.metadata["x1d_true_mpa"]) == 0.04
    assert float(data.metadata["x1h_true_mpa"]) == 0.0005
    for probe in (2, 6):
        c = data.curve(probe)
        assert len(c) == 51 and c.deflection_mm[0] == 0 and np.all(np.diff(c.deflection_mm) > -0.01)


def test_diagnose_without_spaces_is_a_one_line_input_error(tmp_path, capsys):
    from pathlib import Path

    example = Path(__file__).resolve().parents[1] / "data" / "example_measured.csv"
    code = cli.main(["diagnose", str(example), "--out", str(tmp_path / "out"),
                     "--space-dir", str(tmp_path / "no_spaces")])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert len(err.splitlines()) == 1 and "no_spaces" in err


# ------------------------------------------------------------------ seeds, study
@pytest.mark.parametrize("command", ["identify", "diagnose"])
def test_negative_seed_is_a_usage_error(command, capsys, tmp_path):
    extra = ["--objective", "single"] if command == "identify" else []
    code, _, err = run([command, "m.csv", "--out", str(tmp_path), "--seed", "-1", *extra], capsys)
    assert code == 2 and "must be >= 0" in err


def test_study_of_a_missing_folder_is_a_one_line_error(capsys, tmp_path):
    code, _, err = run(["study", str(tmp_path / "nowhere"), "--out", str(tmp_path / "o")], capsys)
    assert code == 2 and "no such study folder" in err and "Traceback" not in err


def test_simulate_writes_the_measured_format_that_identify_reads(monkeypatch, capsys, tmp_path):
    from skinsuction.measured import load_measured

    monkeypatch.setattr("skinsuction.model.simulate", fake_simulate([], converge=False))
    target = tmp_path / "curve.csv"
    code, _, _ = run(["simulate", "--probe", 6, "--x1d", 0.05, "--x1h", 1e-3,
                      "--measured-format", "--out", target], capsys)
    assert code == 3  # stopped at 40 mbar: the file holds the converged part only
    data = load_measured(target)
    assert data.probes == (6.0,) and data.curve(6.0).pressure_mbar[-1] == 40.0
    assert data.metadata["x1d_mpa"] == "0.05"


# ---------------------------------------------------------------- export-inp
def test_export_inp_writes_the_deck_of_a_skin_file(capsys, tmp_path):
    """The deck of a three-layer skin: one material per layer, every ramp pressure a
    step; it says on stderr what it leaves out. With CalculiX on PATH (required in CI)
    the deck runs and agrees with this model without the wall."""
    import os

    from skinsuction.model import Skin, SuctionTest, read_dat

    skin = Skin.two_layer(0.08, 4.1e-4, t_d=0.9).with_layer_on_top("superficial", 0.1, 0.02)
    out = tmp_path / "suction.inp"
    code, _, err = run(["export-inp", "--probe", 2, "--skin", skin.write(tmp_path / "s.yaml"),
                        "--max-mbar", 40, "--step-mbar", 20, "--refinement", 0.5,
                        "--out", out], capsys)
    assert code == 0 and "probe wall" in err and str(out) in err
    deck = out.read_text()
    assert deck.count("*MATERIAL") == 3 and deck.count("*STEP") == 2
    ccx = shutil.which("ccx")
    if ccx is None and os.environ.get("SKINSUCTION_REQUIRE_CCX") != "1":
        return
    run_dir = tmp_path / "ccx"
    run_dir.mkdir()
    (run_dir / "suction.inp").write_text(deck)
    subprocess.run([ccx or "ccx", "suction"], cwd=run_dir, capture_output=True, check=True,
                   timeout=600)
    p, m = read_dat(run_dir / "suction.dat")
    ours = SuctionTest(skin, 2, {"refinement": 0.5, "probe_wall": False}).run([0.0, 20.0, 40.0])
    np.testing.assert_allclose(np.interp([20.0, 40.0], p, m), ours.deflection_mm[1:],
                               rtol=3e-3)


def test_export_inp_refuses_a_prestretched_skin_in_one_line(capsys, tmp_path):
    code, _, err = run(["export-inp", "--probe", 2, "--x1d", 0.08, "--x1h", 4e-4,
                        "--out", tmp_path / "d.inp"], capsys)
    assert code == 0
    skin = tmp_path / "s.yaml"
    skin.write_text("layers: [{name: dermis, thickness: 1, X1: 0.08, prestretch: 1.05}]")
    code, _, err = run(["export-inp", "--probe", 2, "--skin", skin, "--out",
                        tmp_path / "e.inp"], capsys)
    assert code == 2 and err.count("\n") == 1 and "pre-stretch" in err
    assert not (tmp_path / "e.inp").exists()


def test_identify_takes_the_layers_from_a_skin_file(tmp_path, capsys):
    """--skin gives the dermis and hypodermis thicknesses (options override them); a
    stack the spaces do not hold is refused in one line that names its layers."""
    import argparse

    from skinsuction.commands._common import thickness_from_args
    from skinsuction.model import Skin

    path = Skin.two_layer(0.05, 5e-4, t_d=1.3, t_h=2.7).write(tmp_path / "skin.yaml")
    args = argparse.Namespace(skin=str(path), dermis_thickness_mm=None,
                              dermis_thickness_sd_mm=0.1, hypodermis_thickness_mm=None)
    assert thickness_from_args(args) == {"dermis_thickness_mm": 1.3,
                                         "hypodermis_thickness_mm": 2.7,
                                         "dermis_thickness_sd_mm": 0.1}
    args.dermis_thickness_mm = 1.1
    assert thickness_from_args(args)["dermis_thickness_mm"] == 1.1
    three = Skin.read(path).with_layer_on_top("superficial", 0.1, 0.02).write(tmp_path / "3.yaml")
    code, _, err = run(["identify", str(ROOT / "data" / "example_measured.csv"), "--skin",
                        three, "--objective", "weighted", "--out", tmp_path / "out"], capsys)
    assert code == 2 and err.count("\n") == 1 and "superficial" in err
