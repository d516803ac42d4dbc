"""Studies: ids end to end, bad files as rows, the group comparison finds a hidden effect."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from skinsuction.cohort import compare_groups, discover, run_study
from skinsuction.measured import load_table
from test_diagnose import BASELINE, toy_curve, toy_spaces

P = np.arange(0.0, 100.1, 4.0)


def _rows(ids, x1d, r, noise_um, rng, probes=(6.0, 2.0)):
    out = []
    for probe in probes:
        m = toy_curve(x1d, r, 0.0, P, probe, BASELINE) + rng.normal(0, 1e-3 * noise_um, P.size)
        m[0] = 0.0
        out += [f"{ids},{probe:g},{p:g},{v:.6f}" for p, v in zip(P, m)]
    return out


def _long_study(path, n_per_group=8, effect=1.3, seed=0):
    """A long CSV: subjects x 2 visits, treated X1d x effect at visit 2, one broken row."""
    rng = np.random.default_rng(seed)
    lines = ["subject,group,visit,probe_mm,pressure_mbar,deflection_mm"]
    truth = []
    for k in range(2 * n_per_group):
        group = "treated" if k < n_per_group else "control"
        x1d = float(np.exp(rng.uniform(np.log(0.03), np.log(0.1))))
        r = float(np.exp(rng.uniform(np.log(0.02), np.log(0.2))))
        for visit in (1, 2):
            x = x1d * (effect if (group == "treated" and visit == 2) else 1.0)
            x *= float(np.exp(rng.normal(0, 0.03)))
            lines += _rows(f"P{k:02d},{group},{visit}", x, r, 1.0, rng)
            truth.append((f"P{k:02d}", visit, x))
    # a decimal comma in one row of one measurement (P01, visit 2): only it fails
    i = next((j for j, s in enumerate(lines) if s.startswith("P01,treated,2,6,40,")), None)
    if i is not None:
        lines[i] = lines[i].replace("0.", "0,", 1)
    path.write_text("\n".join(lines) + "\n")
    return truth


def _toy_space():
    from skinsuction.space import NeoHookeanSlice
    from skinsuction.identify.measured_fit import LoadedSpace

    spaces = toy_spaces()
    return LoadedSpace.given({p: NeoHookeanSlice(spaces[BASELINE], p) for p in (2.0, 6.0)}), spaces


def test_long_csv_ids_split_measurements_and_a_bad_row_stops_only_its_own(tmp_path):
    path = tmp_path / "study.csv"
    _long_study(path, n_per_group=2)
    entries = load_table(path)
    assert len(entries) == 8
    bad = [e for e in entries if e.error]
    assert [(e.ids["subject"], e.ids["visit"]) for e in bad] == [("P01", "2")]
    assert "line" in bad[0].error and "decimal comma" in bad[0].error
    good = next(e for e in entries if e.ids["subject"] == "P00" and e.ids["visit"] == "1")
    assert good.data.probes == (2.0, 6.0) and len(good.data.curve(6.0)) == P.size
    assert good.data.metadata["group"] == "treated"  # ids travel with the curves


def test_cr_only_line_endings_are_read(tmp_path):
    path = tmp_path / "mac.csv"
    path.write_bytes(b"probe_mm,pressure_mbar,deflection_mm\r6,0,0\r6,50,0.4\r6,100,0.7\r")
    (entry,) = load_table(path)
    assert entry.error is None and entry.data.curve(6.0).deflection_mm.tolist() == [0, 0.4, 0.7]


def test_folder_ids_come_from_headers_and_the_manifest(tmp_path):
    rng = np.random.default_rng(1)
    folder = tmp_path / "study"
    folder.mkdir()
    for name, subject in (("a.csv", "S1"), ("b.csv", "S2")):
        rows = _rows("", 0.05, 0.05, 1.0, rng)
        (folder / name).write_text(f"# subject: {subject}\nprobe_mm,pressure_mbar,deflection_mm\n"
                                   + "\n".join(r.lstrip(",") for r in rows) + "\n")
    (folder / "broken.csv").write_text("probe_mm;pressure_mbar;deflection_mm\n6;0;0\n")
    (folder / "manifest.csv").write_text("file,group,subject\na.csv,treated,S1x\n")
    found = discover(folder)
    ids = {e.ids["file"]: (e.ids, e.error) for e, _ in found}
    assert ids["a.csv"][0]["group"] == "treated" and ids["a.csv"][0]["subject"] == "S1x"
    assert ids["b.csv"][0]["subject"] == "S2" and ids["b.csv"][1] is None
    assert "separated by ','" in ids["broken.csv"][1]
    assert all(len(sha) == 64 for _, sha in found)


def test_study_recovers_the_hidden_treatment_effect_and_reports_the_broken_file(tmp_path):
    path = tmp_path / "study.csv"
    truth = _long_study(path)
    space, _ = _toy_space()
    out = tmp_path / "out"
    r = run_study(path, out, space=space, diagnose=False, repeats=1, seed=3, progress=False)
    df = pd.read_parquet(out / "curves.parquet")
    assert len(df) == 32 and r["errors"] == 1
    assert {"subject", "group", "visit", "x1d_lower_mpa", "sha256", "error"} <= set(df.columns)
    err = df[df["error"].notna()]
    assert err[["subject", "visit"]].values.tolist() == [["P01", "2"]]
    # every estimate against its truth, through the ids: the 95 % intervals cover it
    est = df.dropna(subset=["x1d_mpa"]).set_index(["subject", "visit"])
    inside = [est.loc[(s, str(v)), "x1d_lower_mpa"] <= x <= est.loc[(s, str(v)), "x1d_upper_mpa"]
              for s, v, x in truth if (s, str(v)) in est.index]
    assert len(inside) == 31 and np.mean(inside) >= 0.8
    rows = {c["group"]: c for c in r["comparison"]}
    treated, control = rows["treated"], rows["control"]
    assert treated["n"] == 7 and control["n"] == 8  # P01 has one visit left
    assert treated["p_value"] < 0.02 and control["p_value"] > 0.05
    assert treated["ci_low_percent"] < 30 < treated["ci_high_percent"]
    assert rows["treated vs control"]["p_value"] < 0.01
    summary = (out / "summary.md").read_text()
    assert "P01" in summary and "decimal comma" in summary
    for fig in ("distribution_x1d", "paired_x1d", "causes"):
        assert (out / f"{fig}.png").stat().st_size > 1000


def test_study_diagnoses_each_measurement_in_parallel_with_the_same_result(tmp_path):
    path = tmp_path / "study.csv"
    _long_study(path, n_per_group=1)
    space, rays = _toy_space()
    out = {}
    for workers in (1, 2):
        run_study(path, tmp_path / f"w{workers}", space=space, ray_spaces=rays, diagnose=True,
                  repeats=1, seed=0, workers=workers, progress=False, reports=workers == 1,
                  diagnosis_settings={"window_focusing": {"n_samples": 300}})
        out[workers] = pd.read_parquet(tmp_path / f"w{workers}" / "curves.parquet")
    # the optional per-measurement reports: identification and diagnosis of each
    reports = sorted((tmp_path / "w1" / "reports").iterdir())
    assert len(reports) == 4
    assert (reports[0] / "identification" / "identification.json").exists()
    assert (reports[0] / "diagnosis" / "report.json").exists()
    assert not (tmp_path / "w2" / "reports").exists()
    a, b = out[1], out[2]
    assert a["cause"].notna().sum() == 4
    pd.testing.assert_series_equal(a["x1d_mpa"], b["x1d_mpa"])
    assert a["cause"].tolist() == b["cause"].tolist()


def test_unpaired_groups_are_compared_by_mann_whitney():
    rng = np.random.default_rng(0)
    df = pd.DataFrame({"group": ["a"] * 12 + ["b"] * 12,
                       "x1d_mpa": np.r_[np.exp(rng.normal(np.log(0.02), 0.1, 12)),
                                        np.exp(rng.normal(np.log(0.03), 0.1, 12))]})
    rows, notes = compare_groups(df, reference="a")
    assert "unpaired" in notes[0]
    (row,) = rows
    assert row["test"].startswith("Mann-Whitney") and row["p_value"] < 0.01
    assert 30 < row["median_change_percent"] < 70 and row["effect_size"] > 0.8
    # its bootstrap interval holds the estimate and, at 12 per group, the truth (+50 %)
    assert row["ci_low_percent"] < row["median_change_percent"] < row["ci_high_percent"]
    assert row["ci_low_percent"] < 50 < row["ci_high_percent"]


def test_ramps_and_time_curves_are_compared_apart():
    """One subject's ramp and mode-1 curve are not independent, and a time curve's X1d is
    a long-time modulus: a mixed study is compared protocol by protocol."""
    rng = np.random.default_rng(1)
    n = 12
    x1d = np.r_[np.exp(rng.normal(np.log(0.03), 0.1, n)), np.exp(rng.normal(np.log(0.02), 0.1, n))]
    groups = ["treated"] * n + ["control"] * n
    ramp = pd.DataFrame({"group": groups, "x1d_mpa": x1d, "protocol": None})
    # the time curves' long-time X1d: no group difference at all, another scale
    time = pd.DataFrame({"group": groups, "x1d_mpa": 0.01 * np.exp(rng.normal(0, 0.1, 2 * n)),
                         "protocol": "mode 1"})
    rows, notes = compare_groups(pd.concat([ramp, time], ignore_index=True))
    assert "compared apart" in notes[0]
    by = {r["protocol"]: r for r in rows}
    assert set(by) == {"ramp", "mode 1"} and all(r["n"] == 2 * n for r in rows)
    assert by["ramp"]["p_value"] < 0.01 and by["ramp"]["median_change_percent"] > 30
    assert by["mode 1"]["p_value"] > 0.01
    # one protocol only: as before, no protocol column in the rows
    rows, _ = compare_groups(ramp)
    assert "protocol" not in rows[0]


def test_rows_of_other_code_are_set_aside_not_resumed(tmp_path, monkeypatch):
    """A study cut short, the package then changed: its rows are kept aside, not mixed
    with the new code's (the version string alone would not tell them apart)."""
    import skinsuction.cohort._rows as rows_module
    import skinsuction.provenance as provenance

    path = tmp_path / "study.csv"
    _long_study(path, n_per_group=2)
    space, rays = _toy_space()
    kw = dict(space=space, ray_spaces=rays, diagnose=False, repeats=1, seed=0, progress=False,
              figures=False)
    real, calls = rows_module._analyse, []

    def cut_after_two(job):
        if len(calls) == 2:
            raise KeyboardInterrupt
        calls.append(job[0])
        return real(job)

    monkeypatch.setattr(rows_module, "_analyse", cut_after_two)
    with pytest.raises(KeyboardInterrupt):
        run_study(path, tmp_path / "cut", **kw)
    monkeypatch.setattr(rows_module, "_analyse", real)
    monkeypatch.setattr(provenance, "source_hash", lambda *a, **k: "edited")
    r = run_study(path, tmp_path / "cut", **kw)
    assert r["resumed"] == 0
    assert (tmp_path / "cut" / "rows.partial.jsonl.stale").exists()


def test_a_study_cut_short_resumes_with_the_rows_it_had_finished(tmp_path, monkeypatch):
    import skinsuction.cohort._rows as rows_module

    path = tmp_path / "study.csv"
    _long_study(path, n_per_group=2)
    space, rays = _toy_space()
    kw = dict(space=space, ray_spaces=rays, diagnose=True, repeats=1, seed=0, progress=False,
              figures=False, diagnosis_settings={"window_focusing": {"n_samples": 300}})
    run_study(path, tmp_path / "whole", **kw)
    whole = pd.read_parquet(tmp_path / "whole" / "curves.parquet")

    real, calls = rows_module._analyse, []

    def cut_after_three(job):
        if len(calls) == 3:
            raise KeyboardInterrupt  # the run is killed while analysing the 4th
        calls.append(job[0])
        return real(job)

    monkeypatch.setattr(rows_module, "_analyse", cut_after_three)
    with pytest.raises(KeyboardInterrupt):
        run_study(path, tmp_path / "cut", **kw)
    kept = (tmp_path / "cut" / "rows.partial.jsonl").read_text().splitlines()
    assert len(kept) == 1 + 3 and not (tmp_path / "cut" / "curves.parquet").exists()

    def counted(job):
        calls.append(job[0])
        return real(job)

    calls.clear()
    monkeypatch.setattr(rows_module, "_analyse", counted)
    r = run_study(path, tmp_path / "cut", **kw)
    assert r["resumed"] == 3 and sorted(calls) == list(range(3, len(whole)))
    resumed = pd.read_parquet(tmp_path / "cut" / "curves.parquet")
    pd.testing.assert_frame_equal(resumed.drop(columns="seconds"),
                                  whole.drop(columns="seconds"))
    assert not (tmp_path / "cut" / "rows.partial.jsonl").exists()
    # other settings (another seed): the rows are not reused, and not lost either
    monkeypatch.setattr(rows_module, "_analyse", cut_after_three)
    calls.clear()
    with pytest.raises(KeyboardInterrupt):
        run_study(path, tmp_path / "cut", **{**kw, "seed": 1})
    calls.clear()
    monkeypatch.setattr(rows_module, "_analyse", counted)
    r = run_study(path, tmp_path / "cut", **kw)
    assert r["resumed"] == 0 and len(calls) == len(whole)
    assert (tmp_path / "cut" / "rows.partial.jsonl.stale").exists()
