"""``skinsuction simulate`` in time: --mode1, --mode2, --history, --sample-hz, --rparams.

The real FE model on the coarse mesh (``--refinement 0.5``) under the 2 mm probe,
over protocols of a second or less sampled at 20-100 Hz: each solve takes about a
second. The checks are independent of the time solver: an elastic skin against the
quasi-static ramp of ``simulate`` itself, a creeping skin against the ramps of its
long-time and instantaneous moduli, the written file against the package's own
readers (``read_measurement``, ``r_parameters``).
"""

import io
import re
from contextlib import redirect_stderr, redirect_stdout

import numpy as np
import pandas as pd
import pytest

from skinsuction import cli
from skinsuction.measured import MeasuredTimeData, r_parameters, read_measurement
from skinsuction.model import Prony, Skin

COARSE = ["--probe", 2, "--refinement", 0.5]
ELASTIC = ["--x1d", 0.08, "--x1h", 4.1e-4]


#: a progress line, shown when a solve outlasts a few seconds (a busy machine): not a warning
PROGRESS = re.compile(r"^simulate: \d+/\d+ time steps")


def run(argv, capsys=None):
    """``(exit code, stdout, stderr without progress lines)`` of the command line."""
    argv = [str(a) for a in argv]
    if capsys is not None:
        code = cli.main(argv)
        out, err = capsys.readouterr()
    else:
        out, err = io.StringIO(), io.StringIO()
        with redirect_stdout(out), redirect_stderr(err):
            code = cli.main(argv)
        out, err = out.getvalue(), err.getvalue()
    err = "".join(line for line in err.splitlines(keepends=True)
                  if not PROGRESS.match(line) and line.strip())
    return code, out, err


def csv(text):
    return pd.read_csv(io.StringIO(text), comment="#")


def ramp_end(capsys, skin_args, p_mbar):
    """M(p_mbar) of the quasi-static ramp ``simulate`` (steps of p/9)."""
    code, out, _ = run(["simulate", *COARSE, *skin_args, "--max-mbar", p_mbar,
                        "--step-mbar", p_mbar / 9], capsys)
    assert code == 0
    return float(csv(out)["deflection_mm"].iloc[-1])


@pytest.fixture(scope="module")
def mode1_file(tmp_path_factory):
    """A creeping two-term skin, 2 cycles of 450 mbar 0.5 s on / 0.5 s off at 20 Hz,
    written in the measured format with its R parameters printed."""
    folder = tmp_path_factory.mktemp("mode1")
    spectrum = Prony([0.5, 0.3], [0.01, 0.5])
    skin = Skin.two_layer(0.08, 4.1e-4, spectrum=spectrum).write(folder / "skin.yaml")
    target = folder / "mode1.csv"
    code, out, err = run(["simulate", *COARSE, "--skin", skin, "--mode1", "450,0.5,0.5,2",
                          "--sample-hz", 20, "--measured-format", "--rparams", "--out", target])
    assert code == 0 and err == "", err
    return target, out


# ------------------------------------------------------------------ mode 1
def test_mode1_of_an_elastic_skin_is_the_quasi_static_ramp(capsys):
    code, out, err = run(["simulate", *COARSE, *ELASTIC, "--mode1", "450,0.5,0.5,1",
                          "--sample-hz", 20], capsys)
    assert code == 0 and err == ""
    frame = csv(out)
    assert list(frame.columns) == ["time_s", "pressure_mbar", "deflection_mm"]
    np.testing.assert_allclose(frame["time_s"], np.arange(21) / 20, atol=1e-12)
    hold = frame[frame["pressure_mbar"] == 450]["deflection_mm"]
    off = frame[frame["time_s"] > 0.5]
    assert len(hold) == 10 and (off["pressure_mbar"] == 0).all()
    m450 = ramp_end(capsys, ELASTIC, 450.0)  # the independent check: the ramp to 450
    np.testing.assert_allclose(hold, m450, rtol=1e-6)
    assert np.abs(off["deflection_mm"]).max() < 1e-9 * m450  # back at rest
    assert "# protocol: mode 1, 450 mbar, 0.5 s on / 0.5 s off, 1 cycle" in out
    assert "# converged: true" in out and "# sample_hz: 20" in out


def test_a_creeping_skin_creeps_from_the_instantaneous_to_the_long_time_ramp(capsys,
                                                                            tmp_path):
    """One term, g = 1, tau = 0.05 s (retardation 0.1 s): the first sample of the hold
    is near the ramp of the instantaneous moduli 2 X1, the last (10 retardation times
    on) at the ramp of the long-time moduli X1."""
    skin = Skin.two_layer(0.08, 4.1e-4, spectrum=Prony([1.0], [0.05]))
    code, out, _ = run(["simulate", *COARSE, "--skin", skin.write(tmp_path / "s.yaml"),
                        "--mode1", "450,1,0.5,1", "--sample-hz", 100], capsys)
    assert code == 0
    hold = csv(out).query("pressure_mbar == 450")["deflection_mm"].to_numpy()
    long_time = ramp_end(capsys, ELASTIC, 450.0)
    instantaneous = ramp_end(capsys, ["--x1d", 0.16, "--x1h", 8.2e-4], 450.0)
    assert np.all(np.diff(hold) > 0)  # creep all along the hold
    assert instantaneous < hold[0] < 1.1 * instantaneous  # 0.01 s in: barely crept
    assert hold[-1] == pytest.approx(long_time, rel=1e-3)
    # the creep over the hold, end over start, approaches long-time over instantaneous
    ratio = long_time / instantaneous
    assert ratio > 1.9 and 0.95 * ratio < hold[-1] / hold[0] < ratio


def test_the_measured_format_reads_back_as_a_mode1_time_curve(mode1_file):
    target, _ = mode1_file
    data = read_measurement(target)
    assert isinstance(data, MeasuredTimeData) and data.probes == (2.0,)
    (curve,) = data.curves
    assert curve.protocol == "mode 1" and len(curve.cycles) == 2
    assert [c.level_mbar for c in curve.cycles] == [450.0, 450.0]
    assert len(curve) == 41 and curve.time_s[-1] == pytest.approx(2.0)
    assert data.metadata["protocol"] == "mode 1, 450 mbar, 0.5 s on / 0.5 s off, 2 cycles"
    assert data.metadata["probe_mm"] == "2" and data.warnings == ()


def test_rparams_are_the_packages_r_parameters_of_the_written_curve(mode1_file):
    target, out = mode1_file
    assert out.startswith("R parameters (mm and ratios; Ue read 0.1 s after onset")
    printed = pd.read_csv(io.StringIO("\n".join(out.splitlines()[1:])), sep=r"\s+")
    (curve,) = read_measurement(target).curves
    expected = r_parameters(curve).drop(columns="curve")
    assert list(printed.columns) == list(expected.columns) and len(printed) == 2
    np.testing.assert_allclose(printed.to_numpy(float), expected.to_numpy(float), atol=5e-4)
    assert (printed["Uv"] > 0).all()  # the skin creeps


def test_rparams_without_out_follow_the_curve_on_stdout(capsys):
    code, out, _ = run(["simulate", *COARSE, *ELASTIC, "--mode1", "450,0.5,0.5,1",
                        "--sample-hz", 20, "--rparams"], capsys)
    curve_text, table = out.split("\n\n")
    assert code == 0 and len(csv(curve_text)) == 21
    assert table.startswith("R parameters") and "R9" in table


# ------------------------------------------------------------------ mode 2, history
def test_mode2_of_an_elastic_skin_follows_the_ramp_up_and_down(capsys, tmp_path):
    target = tmp_path / "mode2.csv"
    code, _, err = run(["simulate", *COARSE, *ELASTIC, "--mode2", "450,0.5,0.5,1",
                        "--sample-hz", 20, "--measured-format", "--out", target], capsys)
    assert code == 0 and err == ""
    (curve,) = read_measurement(target).curves
    assert curve.protocol == "mode 2" and len(curve.cycles) == 1
    # 45 mbar a sample up, then down: every sample on the quasi-static ramp M(p)
    code, out, _ = run(["simulate", *COARSE, *ELASTIC, "--max-mbar", 450, "--step-mbar", 45],
                       capsys)
    ramp = csv(out).set_index("pressure_mbar")["deflection_mm"]
    np.testing.assert_allclose(curve.pressure_mbar, np.r_[0:451:45, 405:-1:-45], atol=1e-9)
    # the time solve keeps its tangent while Newton contracts, so the unloaded skin
    # returns to 0 within the solver's tolerance (picometres), not to the bit
    np.testing.assert_allclose(curve.deflection_mm, ramp.loc[np.round(curve.pressure_mbar)],
                               rtol=1e-6, atol=1e-9)


def test_history_file_is_solved_and_sampled(capsys, tmp_path):
    history = tmp_path / "p.csv"
    history.write_text("# a hold of 300 mbar\ntime_s,pressure_mbar\n0,0\n0.02,300\n0.6,300\n"
                       "0.62,0\n1.0,0\n")
    code, out, err = run(["simulate", *COARSE, *ELASTIC, "--history", history,
                          "--sample-hz", 20], capsys)
    assert code == 0 and err == ""
    frame = csv(out)
    np.testing.assert_allclose(frame["time_s"], np.arange(21) / 20, atol=1e-12)
    np.testing.assert_allclose(frame["pressure_mbar"],
                               np.interp(frame["time_s"], [0, 0.02, 0.6, 0.62, 1.0],
                                         [0, 300, 300, 0, 0]), atol=1e-9)
    hold = frame.query("pressure_mbar == 300")["deflection_mm"]
    np.testing.assert_allclose(hold, ramp_end(capsys, ELASTIC, 300.0), rtol=1e-6)
    assert f"# history_file: {history}" in out and "# history_sha256: " in out
    assert "# protocol: history, 5 points, 0 to 1 s, up to 300 mbar" in out


# ------------------------------------------------------------------ bad input
@pytest.mark.parametrize("extra, words", [
    (["--mode1", "450,3,3"], ["--mode1 450,3,3", "expected 4 numbers P,ON,OFF,CYCLES"]),
    (["--mode1", "450,0,3,2"], ["--mode1", "ON = 0 s must be > 0.01 s"]),
    (["--mode1", "450,3,-3,2"], ["--mode1", "OFF = -3 s"]),
    (["--mode1", "0,3,3,2"], ["--mode1", "P = 0 mbar"]),
    (["--mode1", "450,3,3,1.5"], ["--mode1", "CYCLES = 1.5 must be a whole number"]),
    (["--mode1", "450,abc,3,2"], ["--mode1", "ON is not a number"]),
    (["--mode2", "450,3,0,1"], ["--mode2", "FALL = 0 s"]),
    (["--mode1", "450,3,3,2", "--mode2", "450,3,3,1"], ["give one protocol", "--mode1",
                                                        "--mode2"]),
    (["--mode1", "450,3,3,2", "--history", "p.csv"], ["give one protocol", "--history"]),
    (["--rparams"], ["--rparams needs --mode1"]),
    (["--mode2", "450,3,3,1", "--rparams"], ["--rparams needs --mode1, not --mode2"]),
    (["--mode1", "450,3,3,2", "--max-mbar", "450"], ["--max-mbar", "give one protocol"]),
    (["--sample-hz", "50"], ["--sample-hz applies to a time protocol"]),
    (["--mode1", "450,3,3,2", "--sample-hz", "0"], ["--sample-hz"]),
    (["--mode1", "450,0.02,0.02,1", "--sample-hz", "10"], ["--sample-hz 10 gives 1 sample"]),
])
def test_bad_protocol_options_exit_2_naming_the_option(extra, words, capsys):
    code, out, err = run(["simulate", *COARSE, *ELASTIC, *extra], capsys)
    assert code == 2 and out == "" and "Traceback" not in err
    for word in words:
        assert word in err, (word, err)
    if "--sample-hz" not in extra or extra[-1] != "0":  # ours, not argparse's: one line
        assert err.count("\n") == 1


@pytest.mark.parametrize("rows, words", [
    ("time_s,pressure_mbar\n0,0\n0.1,abc\n", ["line 3", "'pressure_mbar'", "not a number"]),
    ("time_s,pressure_mbar\n0,0\n0.5,100\n0.5,100\n", ["line 4", "'time_s'",
                                                       "not after 0.5 s on line 3"]),
    ("time_s,pressure_mbar\n0,0\n0.5,100\n0.4,100\n", ["line 4", "not after"]),
    ("time_s,pressure_mbar\n0,0\n0.5,-100\n", ["line 3", "suction -100 mbar is negative"]),
    ("time,pressure\n0,0\n0.5,100\n", ["line 1", "header must be time_s,pressure_mbar"]),
    ("time_s,pressure_mbar\n0,50\n0.5,100\n", ["line 2", "0 at the first time"]),
    ("time_s,pressure_mbar\n0,0\n0.5,100,3\n", ["line 3", "3 fields, expected 2"]),
    ("time_s,pressure_mbar\n0,0\n", ["at least 2 rows"]),
])
def test_a_malformed_history_names_the_file_and_line(rows, words, capsys, tmp_path):
    history = tmp_path / "history.csv"
    history.write_text(rows)
    code, out, err = run(["simulate", *COARSE, *ELASTIC, "--history", history], capsys)
    assert code == 2 and out == "" and err.count("\n") == 1
    assert str(history) in err
    for word in words:
        assert word in err, (word, err)


def test_a_missing_history_file_is_one_line(capsys, tmp_path):
    code, _, err = run(["simulate", *COARSE, *ELASTIC, "--history", tmp_path / "no.csv"],
                       capsys)
    assert code == 2 and "--history" in err and "cannot read" in err and err.count("\n") == 1
