"""The synthetic study of subjects with their own layers: its files carry what a study
records and nothing of the truth, its draws are reproducible, and the check against
the truth counts what it says it counts."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from skinsuction.evaluation import (
    LayersStudyDesign,
    draw_layers_subject,
    layers_study_check,
    layers_study_markdown,
    make_layers_study,
)

# a coarse mesh and a short protocol: seconds, not the study's minutes
QUICK = LayersStudyDesign(subjects=2, ramp_max_mbar=20.0, mode1_on_off_cycles=(0.3, 0.2, 1),
                          mesh={"refinement": 0.5})


def test_draws_are_reproducible_and_the_given_layers_carry_their_error():
    d = LayersStudyDesign()
    draws = [draw_layers_subject(d, i) for i in range(200)]
    assert draws[7] == draw_layers_subject(d, 7)  # by subject, not by process
    assert draw_layers_subject(d, 7, attempt=1) != draws[7]
    assert [x["group"] for x in draws].count("treated") == 100
    t_d = np.array([x["t_d_mm"] for x in draws])
    err = np.array([x["t_d_given_mm"] - x["t_d_mm"] for x in draws])
    assert 0.5 <= t_d.min() and t_d.max() <= 2.5
    # the given thickness is the truth plus N(0, 0.1 mm), written to 0.01 mm
    assert 0.08 < err.std() < 0.12 and abs(err.mean()) < 0.03
    x1d = np.array([x["x1d_mpa"] for x in draws])
    assert x1d[:100].min() >= 0.008 * 1.25 and x1d[100:].max() <= 0.08


def test_the_files_hold_the_ids_and_given_layers_and_no_truth(tmp_path):
    from skinsuction.cohort import discover

    truth = make_layers_study(tmp_path / "study", tmp_path / "truth.csv", QUICK)
    assert sorted(truth["file"]) == ["S001_mode1.csv", "S001_ramp.csv", "S002_mode1.csv",
                                     "S002_ramp.csv"]
    text = (tmp_path / "study" / "S001_ramp.csv").read_text()
    assert "true" not in text.lower().replace("the truth is kept apart", "")
    assert f"{truth['x1d_mpa'].iloc[0]:.6g}" not in text
    found = {e.ids["file"]: e for e, _ in discover(tmp_path / "study")}
    ramp = found["S001_ramp.csv"]
    assert ramp.error is None
    assert ramp.ids["subject"] == "S001" and ramp.ids["group"] == "treated"
    row = truth[truth["file"] == "S001_ramp.csv"].iloc[0]
    assert float(ramp.ids["dermis_thickness_mm"]) == pytest.approx(row["t_d_given_mm"])
    assert float(ramp.ids["hypodermis_thickness_sd_mm"]) == pytest.approx(0.1)
    mode1 = found["S001_mode1.csv"]
    assert mode1.error is None and mode1.ids["measurement"] == "mode 1"
    assert mode1.data.geometry["hypodermis_thickness_mm"] == pytest.approx(row["t_h_given_mm"])
    again = make_layers_study(tmp_path / "again", tmp_path / "truth2.csv", QUICK)
    assert (tmp_path / "again" / "S002_mode1.csv").read_bytes() == \
        (tmp_path / "study" / "S002_mode1.csv").read_bytes()
    pd.testing.assert_frame_equal(truth, again)


def test_the_check_counts_coverage_verdicts_and_the_group_ratio():
    truth = pd.DataFrame({
        "file": [f"S{i}_ramp.csv" for i in range(8)], "measurement": "ramp",
        "group": ["treated"] * 4 + ["control"] * 4,
        "x1d_mpa": [0.025, 0.030, 0.035, 0.040, 0.020, 0.024, 0.028, 0.032],
        "x1h_mpa": 1e-3})
    est = truth["x1d_mpa"].to_numpy() * np.r_[1.01, 0.99, 1.0, 1.2, 1.0, 1.0, 1.0, 1.0]
    curves = pd.DataFrame({
        "file": ["sub/" + f for f in truth["file"]], "x1d_mpa": est,
        "x1d_lower_mpa": est * 0.98, "x1d_upper_mpa": est * 1.02,  # S3: 20 % off, not held
        "x1h_mpa": 1e-3, "x1h_lower_mpa": [np.nan] * 8, "x1h_upper_mpa": 2e-3,  # open below
        "cause": ["none"] * 7 + ["strain_stiffening"],
        "verdict": ["neo_hookean_fits"] * 6 + ["beyond_space", "cause_found"]})
    check = layers_study_check(curves, truth)
    (row,) = check["per_measurement"]
    assert (row["n"], row["x1d_covered"], row["x1h_covered"]) == (8, 7, 8)
    # an end flagged open (its value the space's edge) holds what lies beyond it
    edge = curves.assign(x1h_lower_mpa=1.5e-3, x1h_lower_open=[True] * 4 + [False] * 4)
    (row_edge,) = layers_study_check(edge, truth)["per_measurement"]
    assert row_edge["x1h_covered"] == 4
    assert row["x1d_error_median"] == pytest.approx(0.0, abs=1e-12)
    assert row["causes"] == "none 7; strain_stiffening 1"
    assert row["verdicts"] == "beyond_space 1; cause_found 1; neo_hookean_fits 6"
    on = {g["on"]: g for g in check["groups"]}
    # the study's statistic, the change of the median log X1d: each treated truth is
    # 1.25 x a control one, so +25 % exactly
    assert on["truth"]["median_change_percent"] == pytest.approx(25.0)
    log = np.log(est)
    expected = np.exp(np.median(log[:4]) - np.median(log[4:])) - 1
    assert on["estimates"]["median_change_percent"] == pytest.approx(100 * expected)
    assert on["truth"]["n"] == 8 and on["truth"]["ci_low_percent"] <= 25.0
    md = layers_study_markdown(check, LayersStudyDesign(subjects=8), seconds=12.0)
    assert "7 (88 %)" in md and "+25.0 %" in md and "| beyond_space 1;" in md
    with pytest.raises(ValueError, match="without a truth"):
        layers_study_check(curves.assign(file="other.csv"), truth)
