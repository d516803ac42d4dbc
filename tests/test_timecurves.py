"""Time curves (Cutometer mode 1 and mode 2) and the standard R parameters.

The R values are checked against a Kelvin-Voigt creep curve whose readings are known
in closed form: under a suction step the deflection is ``J(s) = U0 + A (1 - exp(-s /
TAU))`` (an elastic jump and one Kelvin-Voigt term), and after the release the
superposition ``J(s) - J(s - T)``.  The expected values are written out from ``J`` at
the reading times of the documented convention, not computed by the code under test.
"""

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from skinsuction import cli
from skinsuction.measured import (
    MeasuredDataError,
    R_COLUMNS,
    is_time_curve_file,
    load_time_curves,
    r_parameters,
    ramp_parameters,
)

ROOT = Path(__file__).resolve().parents[1]
HEADER = "probe_mm,time_s,pressure_mbar,deflection_mm"
U0, A, TAU = 0.40, 0.20, 0.5          # mm, mm, s
P = 400.0                              # mbar
T_ON, T_OFF, START = 3.0, 2.0, 0.5     # s
RATE = 1000.0                          # Hz: the switches fall on samples


def J(s):
    """Creep of a 400 mbar step, s after it (0 before)."""
    s = np.asarray(s, dtype=float)
    return np.where(s >= 0, U0 + A * (1 - np.exp(-np.clip(s, 0, None) / TAU)), 0.0)


def mode1(cycles=3, rate=RATE, t_on=T_ON, t_off=T_OFF, levels=None):
    """Samples t, p, d of `cycles` steps (onsets at START + k (t_on + t_off))."""
    n = int(round((START + cycles * (t_on + t_off)) * rate))
    t = np.arange(n) / rate
    p, d = np.zeros(n), np.zeros(n)
    for k in range(cycles):
        on = START + k * (t_on + t_off)
        off = on + t_on
        level = P if levels is None else levels[k]
        # on samples: the switch times are whole numbers of samples
        i_on, i_off = int(round(on * rate)), int(round(off * rate))
        p[i_on:i_off] = level
        d += level / P * (J(t - t[i_on]) - J(t - t[i_off]))
    return t, p, d


def write(path, t, p, d, probe=6, fmt_d="{:.12f}", curve=None, header=HEADER, pre=()):
    rows = [f"{probe:g},{ti:.6f},{pi:.6g}," + fmt_d.format(di)
            + (f",{curve}" if curve is not None else "") for ti, pi, di in zip(t, p, d)]
    head = header + (",curve" if curve is not None else "")
    path.write_text("\n".join([*pre, head, *rows]) + "\n", encoding="utf-8")
    return path


def load_one(tmp_path, *args, **kw):
    return load_time_curves(write(tmp_path / "c.csv", *args, **kw)).curves[0]


# ------------------------------------------------------------------ R parameters
def expected_first_cycle(ue, dt=1 / RATE, t_on=T_ON, t_off=T_OFF):
    """The readings of the first cycle in closed form (a cycle followed by another:
    its off time ends one sample before the next onset)."""
    ue_, uf = float(J(ue)), float(J(t_on - dt))                  # Uf: last sample of the hold
    after_release = float(J(t_on + ue) - J(ue))                   # d, ue after the release
    end = float(J(t_on + t_off - dt) - J(t_off - dt))             # d at the end of the off time
    ur, ua = uf - after_release, uf - end
    return dict(Ue=ue_, Uv=uf - ue_, Uf=uf, Ur=ur, Ua=ua, R0=uf, R1=uf - ua, R2=ua / uf,
                R5=ur / ue_, R6=(uf - ue_) / ue_, R7=ur / uf, R8=ua)


def test_r_values_of_kelvin_voigt_creep_match_the_closed_form(tmp_path):
    c = load_one(tmp_path, *mode1(cycles=3))
    assert c.protocol == "mode 1" and len(c.cycles) == 3
    rows = r_parameters(c)
    assert list(rows.columns) == list(R_COLUMNS) and list(rows.cycle) == [1, 2, 3]
    first = rows.iloc[0]
    for key, value in expected_first_cycle(0.1).items():
        assert first[key] == pytest.approx(value, rel=1e-9, abs=1e-11), key
    # later cycles start from the residual of the earlier ones (superposition): each
    # row is read from the deflection at the end of the previous off time
    t, _, d = mode1(cycles=3)
    period = T_ON + T_OFF
    for k in (1, 2):
        on = START + k * period
        base = float(d[int(round(on * RATE)) - 1])
        uf = float(sum(J(on + T_ON - 1e-3 - (START + j * period))
                       - J(on + T_ON - 1e-3 - (START + j * period) - T_ON) for j in range(k + 1)))
        assert rows.Uf[k] == pytest.approx(uf - base, rel=1e-9)
        assert rows.Ue[k] == pytest.approx(float(
            sum(J(on + 0.1 - (START + j * period)) - J(on + 0.1 - (START + j * period) - T_ON)
                for j in range(k + 1))) - base, rel=1e-9)
    # R3, R4: the last cycle's largest deflection (end of its hold) and smallest (end of
    # the file); R9 = R3 - R0 of the first cycle, on every row
    last_on = START + 2 * period
    r3 = float(sum(J(last_on + T_ON - 1e-3 - (START + j * period))
                   - J(last_on - 1e-3 - (START + j * period)) for j in range(3)))
    r4 = float(d[-1])
    assert np.allclose(rows.R3, r3, rtol=1e-9) and np.allclose(rows.R4, r4, rtol=1e-9)
    assert np.allclose(rows.R9, r3 - float(J(T_ON - 1e-3)), rtol=1e-9)
    # a creeping solid: Uv > 0, and the linear solid gives Ur close to Ue (R5 ~ 1)
    assert (rows.Uv > 0.05).all() and abs(first.R5 - 1) < 0.01


@pytest.mark.parametrize("ue", [0.05, 0.2])
def test_the_ue_reading_time_changes_ue_and_uv_as_the_closed_form_says(tmp_path, ue):
    c = load_one(tmp_path, *mode1(cycles=2))
    at_default, at_ue = r_parameters(c).iloc[0], r_parameters(c, ue_time_s=ue).iloc[0]
    want = expected_first_cycle(ue)
    for key in ("Ue", "Uv", "Ur", "R5", "R6", "R7"):
        assert at_ue[key] == pytest.approx(want[key], rel=1e-9), key
    # Ue moves by the creep between the two reading times, Uv by as much the other way;
    # Uf and Ua are not read at that time and do not move
    shift = float(J(ue) - J(0.1))
    assert at_ue.Ue - at_default.Ue == pytest.approx(shift, rel=1e-9)
    assert at_ue.Uv - at_default.Uv == pytest.approx(-shift, rel=1e-9)
    assert (at_ue.Uf, at_ue.Ua) == (at_default.Uf, at_default.Ua)


def test_a_ue_time_longer_than_the_hold_is_refused(tmp_path):
    c = load_one(tmp_path, *mode1(cycles=2))
    with pytest.raises(ValueError, match="not shorter than the hold of cycle 1"):
        r_parameters(c, ue_time_s=3.5)


def test_a_last_cycle_cut_at_its_release_has_no_recovery(tmp_path):
    t, p, d = mode1(cycles=2)
    keep = t < START + (T_ON + T_OFF) + T_ON + 0.05  # the file stops 50 ms after release
    rows = r_parameters(load_one(tmp_path, t[keep], p[keep], d[keep]))
    assert np.isfinite(rows.loc[0, ["Ur", "Ua", "R2"]].astype(float)).all()
    assert rows.loc[1, ["Ur", "Ua", "R1", "R2", "R5", "R7", "R8"]].isna().all()
    assert np.isfinite(rows.loc[1, ["Ue", "Uf", "R6", "R3", "R4"]].astype(float)).all()


# ------------------------------------------------------------------ quantisation, noise
def test_quantisation_is_reported_and_sets_the_noise_floor_not_flagged(tmp_path):
    t, p, d = mode1(cycles=3, rate=100.0)
    q = 0.01
    c = load_one(tmp_path, t, p, q * np.round(d / q), fmt_d="{:.2f}")
    assert c.resolution_mm == q
    assert c.quantisation_sd_mm == pytest.approx(q / math.sqrt(12))
    # no noise besides the rounding: the estimate is the rounding's sd, not less
    assert c.noise_sd_mm == pytest.approx(q / math.sqrt(12))
    assert any("quantisation, not noise" in n for n in c.notes)
    data = load_time_curves(tmp_path / "c.csv")
    assert data.warnings == ()
    # the R values are within half a step of the closed form (one rounded reading each)
    first = r_parameters(c).iloc[0]
    want = expected_first_cycle(0.1, dt=0.01)
    for key in ("Ue", "Uf"):
        assert abs(first[key] - want[key]) <= q / 2 + 1e-12, key
    for key in ("Uv", "Ur", "Ua"):
        assert abs(first[key] - want[key]) <= q + 1e-12, key


def test_noise_on_a_quantised_curve_is_estimated_with_the_rounding(tmp_path):
    t, p, d = mode1(cycles=4, rate=100.0)
    rng = np.random.default_rng(3)
    sd, q = 0.004, 0.01
    c = load_one(tmp_path, t, p, q * np.round((d + rng.normal(0, sd, d.size)) / q),
                 fmt_d="{:.2f}")
    assert c.resolution_mm == q
    truth = math.sqrt(sd ** 2 + q ** 2 / 12)
    assert c.noise_sd_mm == pytest.approx(truth, rel=0.15)


def test_an_unquantised_curve_has_no_resolution(tmp_path):
    t, p, d = mode1(cycles=2, rate=100.0)
    rng = np.random.default_rng(0)
    c = load_one(tmp_path, t, p, d + rng.normal(0, 0.002, d.size))
    assert c.resolution_mm is None and c.quantisation_sd_mm == 0
    assert c.noise_sd_mm == pytest.approx(0.002, rel=0.15)


# ------------------------------------------------------------------ phases
def test_mode1_phases_of_the_shipped_example():
    data = load_time_curves(ROOT / "data" / "example_mode1.csv")
    c = data.curve(6)
    assert c.protocol == "mode 1" and [k.kind for k in c.cycles] == ["step"] * 5
    onsets = np.array([c.time_s[k.onset] for k in c.cycles])
    releases = np.array([c.time_s[k.release] for k in c.cycles])
    switch = 0.503 + 5.0 * np.arange(5)   # the generator's valve times
    # the first sample after the switch (100 Hz) is the onset, and the release
    assert np.all((onsets > switch) & (onsets <= switch + 0.01))
    assert np.all((releases > switch + 3) & (releases <= switch + 3.01))
    assert all(abs(k.level_mbar - 400) < 3 for k in c.cycles)
    labels = c.phases()
    assert labels[0] == "off" and labels[c.cycles[0].hold_start + 10] == "hold"
    assert set(labels) <= {"off", "rise", "hold", "release"}


def test_phases_are_robust_to_pressure_noise_and_spikes(tmp_path):
    t, p, d = mode1(cycles=3, rate=200.0)
    rng = np.random.default_rng(1)
    noisy = p + rng.normal(0, 4.0, p.size)
    noisy[[150, 151, 1500 + 1000]] = 350.0       # two-sample and one-sample spikes while off
    c = load_one(tmp_path, t, noisy, d)
    assert c.protocol == "mode 1" and len(c.cycles) == 3
    assert [float(c.time_s[k.onset]) for k in c.cycles] == pytest.approx([0.5, 5.5, 10.5])
    assert 2.0 < c.pressure_noise_mbar < 6.0


def test_mode2_phases_and_ramp_parameters_of_the_shipped_example():
    c = load_time_curves(ROOT / "data" / "example_mode2.csv").curve(6)
    assert c.protocol == "mode 2" and [k.kind for k in c.cycles] == ["ramp"]
    k = c.cycles[0]
    # generator: 25 mbar/s from 1.003 s to 400 mbar at 17.003 s, back at 0 at 33.003 s
    assert abs(c.time_s[k.onset] - 1.003) <= 0.02
    assert abs(c.time_s[k.off] - 33.003) <= 0.03
    assert abs(k.level_mbar - 400) < 6
    with pytest.raises(ValueError, match="not mode 1"):
        r_parameters(c)
    row = ramp_parameters(c).iloc[0]
    assert row.rate_mbar_s == pytest.approx(25.0, rel=0.01)
    assert 0.7 < row.Umax < 0.8 and row.hysteresis_mbar_mm > 0


def triangle(rate_mbar_s=25.0, top=400.0, a=A, hz=100.0):
    """A ramp up and down from t = 1 s, the deflection of J with creep term a."""
    T = top / rate_mbar_s
    t = np.arange(int((2 * T + 4) * hz)) / hz
    s = np.clip(t - 1.0, 0, None)
    p = np.where(s <= T, rate_mbar_s * s, np.clip(top - rate_mbar_s * (s - T), 0, None))

    def Jint(x):  # integral of J from 0 to x, per mbar
        x = np.clip(x, 0, None)
        return (U0 * x + a * (x - TAU * (1 - np.exp(-x / TAU)))) / P

    # d = r (Jint(s) - 2 Jint(s - T) + Jint(s - 2T)): the slope r, then -r, then 0
    d = rate_mbar_s * (Jint(s) - 2 * Jint(s - T) + Jint(s - 2 * T))
    return t, p, d, T, Jint


def test_ramp_residual_matches_the_closed_form_and_elastic_has_no_hysteresis(tmp_path):
    t, p, d, T, Jint = triangle()
    c = load_one(tmp_path, t, p, d)
    assert c.protocol == "mode 2"
    assert c.time_s[c.cycles[0].onset] == pytest.approx(1.0)
    row = ramp_parameters(c).iloc[0]
    # when the suction is back at 0 (s = 2T): d = r (Jint(2T) - 2 Jint(T))
    assert row.Ures == pytest.approx(float(25.0 * (Jint(2 * T) - 2 * Jint(T))), rel=1e-6)
    assert row.hysteresis_fraction > 0.01
    te, pe, de, _, _ = triangle(a=0.0)
    elastic = ramp_parameters(load_one(tmp_path, te, pe, de)).iloc[0]
    assert abs(elastic.hysteresis_fraction) < 1e-6 and abs(elastic.Ures) < 1e-9
    assert elastic.Umax == pytest.approx(U0, rel=1e-6)


def test_steps_at_different_levels_are_another_protocol(tmp_path):
    c = load_one(tmp_path, *mode1(cycles=2, levels=[200.0, 400.0]))
    assert c.protocol == "other" and [k.kind for k in c.cycles] == ["step", "step"]
    with pytest.raises(ValueError, match="other, not mode 1"):
        r_parameters(c)


# ------------------------------------------------------------------ located errors
def located(tmp_path, text, line, column, match):
    path = tmp_path / "bad.csv"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(MeasuredDataError, match=match) as info:
        load_time_curves(path)
    err = info.value
    assert (err.line, err.column) == (line, column), str(err)
    assert str(err).startswith(f"{path}, line {line}") and "\n" not in str(err)
    return err


def good_rows(rate=100.0, cycles=2):
    t, p, d = mode1(cycles=cycles, rate=rate)
    return [f"6,{ti:.2f},{pi:g},{di:.4f}" for ti, pi, di in zip(t, p, d)]


def test_time_not_increasing_is_located(tmp_path):
    rows = good_rows()
    rows[40] = rows[40].replace("0.40", "0.38", 1)            # file line 42
    located(tmp_path, "\n".join([HEADER, *rows]), 42, "time_s", "times must strictly increase")
    rows = good_rows()
    rows[40] = rows[40].replace("0.40", "0.39", 1)
    located(tmp_path, "\n".join([HEADER, *rows]), 42, "time_s", "repeats")


@pytest.mark.parametrize("scale, match", [
    (100.0, "looks like Pa, not mbar"),                  # Pa: 40 000
    (2.0, "above the device range"),                      # 800 mbar
    (1e-3, "looks like bar or kPa"),                      # bar: 0.4
    (-1.0, "negative; give the suction as positive"),
])
def test_pressure_out_of_the_device_range_is_located(tmp_path, scale, match):
    t, p, d = mode1(cycles=2, rate=100.0)
    rows = [f"6,{ti:.2f},{scale * pi:g},{di:.4f}" for ti, pi, di in zip(t, p, d)]
    k = int(np.argmin(scale * p)) if scale < 0 else int(np.argmax(scale * p))
    located(tmp_path, "\n".join([HEADER, *rows]), k + 2, "pressure_mbar", match)


def test_a_negative_pressure_beyond_the_sensor_noise_is_located(tmp_path):
    rows = good_rows()
    rows[10] = "6,0.10,-60,0.0000"
    located(tmp_path, "\n".join([HEADER, *rows]), 12, "pressure_mbar", "below zero beyond")


@pytest.mark.parametrize("scale, match", [(1000.0, "looks like µm"), (1e-3, "looks like metres")])
def test_deflection_units_are_located(tmp_path, scale, match):
    t, p, d = mode1(cycles=2, rate=100.0)
    rows = [f"6,{ti:.2f},{pi:g},{scale * di:.9g}" for ti, pi, di in zip(t, p, d)]
    located(tmp_path, "\n".join([HEADER, *rows]), int(np.argmax(d)) + 2, "deflection_mm", match)


def test_a_curve_that_does_not_rise_with_the_suction_is_located(tmp_path):
    t, p, _ = mode1(cycles=2, rate=100.0)
    rng = np.random.default_rng(2)
    d = 0.01 * rng.integers(-1, 2, t.size)          # one quantum of jitter, no dome
    rows = [f"6,{ti:.2f},{pi:g},{di:.2f}" for ti, pi, di in zip(t, p, d)]
    hold_end = int(round((START + T_ON) * 100)) - 1
    located(tmp_path, "\n".join([HEADER, *rows]), hold_end + 2, "deflection_mm",
            "does not rise when the suction is on")


def test_a_curve_that_falls_with_the_suction_is_located(tmp_path):
    t, p, d = mode1(cycles=2, rate=100.0)
    rows = [f"6,{ti:.2f},{pi:g},{0.7 - di:.4f}" for ti, pi, di in zip(t, p, d)]
    hold_end = int(round((START + T_ON) * 100)) - 1
    located(tmp_path, "\n".join([HEADER, *rows]), hold_end + 2, "deflection_mm",
            "falls when the suction is on")


def test_too_few_samples_and_a_short_hold_are_located(tmp_path):
    rows = good_rows()[:15]
    located(tmp_path, "\n".join([HEADER, *rows]), 16, None, "has 15 samples; need >= 20")
    t, p, d = mode1(cycles=4, rate=2.0, t_on=1.0, t_off=3.0)  # 1 s on at 2 Hz
    rows = [f"6,{ti:.2f},{pi:g},{di:.4f}" for ti, pi, di in zip(t, p, d)]
    # a suction of 2 samples is a spike to the phase finder: refused as too slow
    located(tmp_path, "\n".join([HEADER, *rows]), 3, "pressure_mbar",
            "no suction lasting more than 2 samples .* sample faster")


def test_header_errors_name_the_time_curve_format(tmp_path):
    located(tmp_path, "probe_mm,pressure_mbar,deflection_mm\n6,0,0\n", 1, "time_s",
            "a pressure ramp")
    located(tmp_path, "probe_mm,time_ms,pressure_mbar,deflection_mm\n6,0,0,0\n", 1, "time_ms",
            "divide ms by 1000")


def test_is_time_curve_file(tmp_path):
    assert is_time_curve_file(ROOT / "data" / "example_mode1.csv")
    assert not is_time_curve_file(ROOT / "data" / "example_measured.csv")
    assert not is_time_curve_file(tmp_path / "missing.csv")


# ------------------------------------------------------------------ the command
def run(argv, capsys):
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_rparams_command_on_the_mode1_example(tmp_path, capsys):
    code, out, err = run(["rparams", ROOT / "data" / "example_mode1.csv", "--out", tmp_path,
                          "--ue-time-s", "0.2"], capsys)
    assert code == 0, err
    table = pd.read_csv(tmp_path / "rparams.csv")
    assert list(table.columns) == [c for c in R_COLUMNS if c != "curve"]
    assert list(table.cycle) == [1, 2, 3, 4, 5] and (table.probe_mm == 6).all()
    record = json.loads((tmp_path / "rparams.json").read_text())
    assert record["settings"] == {"ue_time_s": 0.2}
    assert record["skinsuction_version"] and record["provenance"]["versions"]["numpy"]
    assert record["curves"][0]["protocol"] == "mode 1"
    assert record["curves"][0]["resolution_mm"] == 0.01
    assert "R5" in out and "quantisation" in out
    assert not list(tmp_path.glob(".*tmp*"))  # the atomic writer left nothing behind


def test_rparams_command_on_the_mode2_example(tmp_path, capsys):
    code, out, err = run(["rparams", ROOT / "data" / "example_mode2.csv", "--out", tmp_path],
                         capsys)
    assert code == 0, err
    assert pd.read_csv(tmp_path / "rparams.csv").empty
    ramp = pd.read_csv(tmp_path / "ramp_parameters.csv")
    assert list(ramp.columns)[:3] == ["probe_mm", "cycle", "p_max_mbar"] and len(ramp) == 1
    assert "do not apply" in out


def test_rparams_command_names_curves_and_refuses_bad_input(tmp_path, capsys):
    t, p, d = mode1(cycles=2, rate=100.0)
    path = tmp_path / "two.csv"
    rows = [f"6,{ti:.2f},{pi:g},{di:.4f},{c}" for c in ("A", "B")
            for ti, pi, di in zip(t, p, d)]
    path.write_text("\n".join([HEADER + ",curve", *rows]) + "\n")
    code, _, err = run(["rparams", path, "--out", tmp_path / "out"], capsys)
    assert code == 0, err
    table = pd.read_csv(tmp_path / "out" / "rparams.csv")
    assert list(table.columns)[:3] == ["probe_mm", "curve", "cycle"]
    assert list(table.curve) == ["A", "A", "B", "B"]
    code, _, err = run(["rparams", ROOT / "data" / "example_measured.csv", "--out",
                        tmp_path / "bad"], capsys)
    assert code == 2 and err.count("\n") == 1 and "line 10" in err and "time_s" in err
    code, _, err = run(["rparams", path, "--out", tmp_path / "bad", "--ue-time-s", "5"],
                       capsys)
    assert code == 2 and "not shorter than the hold" in err
