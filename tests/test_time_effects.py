"""Several effects in one time curve (issue 35): the fast path on a stiffening skin's
elastic curve, the diagnosis that builds the model effect by effect, its rule.

The virtual experiments are FE time solves (``virtual_skin_curve``: internal variables,
implicit steps), independent of the fast path and of the space the diagnosis reads.
"""

import numpy as np
import pytest

from skinsuction.diagnose import Settings
from skinsuction.diagnose._time import VISCOELASTIC_CREEP, diagnose_time_data, write_time_report
from skinsuction.diagnose._time_effects import (CREEP_SECOND_TERM, FINISH_MARGIN_BIC,
                                                EffectFitter, TimeModel, select_effects)
from skinsuction.diagnose._time_layers import cycle_pattern
from skinsuction.evaluation import mode1_suction, virtual_skin_curve, write_time_csv
from skinsuction.identify import TimeCurveModel
from skinsuction.identify.time_curves import prepare_time_fit
from skinsuction.measured import load_time_curves
from skinsuction.model import Skin
from skinsuction.viscoelastic import Prony

FAST = Settings(repeats=1, window_focusing={"n_samples": 600, "n_best": 20,
                                            "tolerance": 1e-6, "max_iter": 40})
STIFF = "strain_stiffening"


@pytest.fixture(scope="module")
def space():
    from skinsuction.space import load_space

    return load_space()


def _skin_file(path, skin, probes=(6.0, 2.0)):
    suction = mode1_suction(400.0, on_s=2.0, off_s=1.5, cycles=1)
    curves = []
    for k, probe in enumerate(probes):
        t, p, d, _, _ = virtual_skin_curve(skin, suction, probe_mm=probe, seed=20 + k)
        curves.append((probe, t, p, d))
    return load_time_curves(write_time_csv(path, curves, ["synthetic: FE"]))


@pytest.fixture(scope="module")
def creep_and_stiffening(tmp_path_factory):
    skin = Skin.two_layer(0.1, 0.005, x2d=0.5, spectrum=Prony([0.4], [0.3]))
    return _skin_file(tmp_path_factory.mktemp("pair") / "pair.csv", skin)


def test_stiffening_rays_at_their_neutral_node_are_the_neo_hookean_model(space,
                                                                         creep_and_stiffening):
    prep = prepare_time_fit(creep_and_stiffening, space)
    rays, _ = prep["space"].cause_rays(STIFF, sorted(prep["rays"]))
    plain = TimeCurveModel(prep["rays"], prep["data"], terms=1)
    stiff = TimeCurveModel(rays, prep["data"], terms=1)
    assert stiff.k0 == 3 and stiff.names[2] == f"{STIFF} axis"
    theta = np.array([np.log10(0.1), np.log10(0.05), np.log10(0.4), np.log10(0.3)])
    with_cause = np.concatenate([theta[:2], [0.0], theta[2:]])  # X2d = 0
    for a, b in zip(plain(theta[None]), stiff(with_cause[None])):
        np.testing.assert_allclose(b, a, rtol=1e-12, atol=0)
    assert stiff.parameters(with_cause)["X2d"] == 0.0


def test_fast_path_on_a_stiffening_skin_against_fe_time_solves(space, creep_and_stiffening):
    """The fast path drives the stiffening skin's elastic curve (from the space); against
    the FE time solve of the same skin it stays within the model error it is given:
    0.5 % of the curve while the suction is on, 2.5 % right after the release."""
    prep = prepare_time_fit(creep_and_stiffening, space)
    rays, _ = prep["space"].cause_rays(STIFF, sorted(prep["rays"]))
    model = TimeCurveModel(rays, prep["data"], terms=1)
    cause = rays[6.0].cause
    theta = np.array([np.log10(0.1), np.log10(0.05), cause.to_axis(5.0),
                      np.log10(0.4), np.log10(0.3)])
    assert model.parameters(theta)["X2d"] == pytest.approx(0.5)
    skin = Skin.two_layer(0.1, 0.005, x2d=0.5, spectrum=Prony([0.4], [0.3]))
    suction = mode1_suction(400.0, on_s=2.0, off_s=1.5, cycles=1)
    for d, m in zip(prep["data"], model(theta[None])):
        _, _, _, exact, _ = virtual_skin_curve(skin, suction, probe_mm=d.probe_mm,
                                               noise_mm=0.0, resolution_mm=0.0)
        err = np.abs(m[0] - exact) / exact.max()
        assert err[d.phase == "on"].max() < 0.005, d.label
        assert err[d.phase == "release"].max() < 0.025, d.label
        # and the stiffening matters: the neo-Hookean curve of the same moduli is off
        # by several times the fast path's error while the suction is on
        plain = TimeCurveModel(prep["rays"], [d], terms=1)(np.delete(theta, 2)[None])[0][0]
        on = d.phase == "on"
        assert np.abs(plain - exact)[on].max() / exact.max() > 3 * err[on].max(), d.label


def test_creep_and_stiffening_are_both_named_with_gains_and_intervals(space,
                                                                     creep_and_stiffening,
                                                                     tmp_path, monkeypatch):
    import skinsuction.identify._time_correction as tc

    solves, solve = [], tc.fe_time_curve
    monkeypatch.setattr(tc, "fe_time_curve",
                        lambda skin, d, mesh=None: solves.append(d.label) or solve(skin, d, mesh))
    r = diagnose_time_data(creep_and_stiffening, space, FAST)
    # creep's fit is corrected in 2 steps of an FE solve per curve; a model adding an
    # effect to a corrected one holds that one's correction for its first step: 1 solve,
    # and none where its BIC is too far from the choice to matter (held)
    options = [o for s in r["steps"] for o in s["options"] if o["fast_path_chi2"] is not None]
    warm = [o for o in options if o["fe_correction_from"]]
    assert len(warm) == len(options) - 1 >= 2
    assert all(set(o["fe_correction_from"].split("+")) < set(o["effects"]) for o in warm)
    for s in r["steps"]:
        best = min(o["bic"] for o in s["options"])
        for o in s["options"]:
            if o["fe_correction_held"]:
                assert o["bic"] - best >= FINISH_MARGIN_BIC and not o["decisive"]
                assert o["delta_bic"] > FAST.delta_bic + FINISH_MARGIN_BIC
    finished = [o for o in warm if not o["fe_correction_held"]]
    assert 1 <= len(finished) < len(warm)
    layer_fits = (r["creep_layers"].get("fe_correction") or {}).values()
    per_layer = sum(bool(f.get("applied")) for f in layer_fits)
    assert len(solves) == 2 * (2 + len(finished) + 2 * per_layer)
    assert r["effects"] == [VISCOELASTIC_CREEP, STIFF], r["summary"]
    assert r["cause"] == r["named"] == VISCOELASTIC_CREEP and r["verdict"] == "cause_found"
    steps = [s for s in r["steps"] if s["added"]]
    assert [s["added"] for s in steps] == r["effects"]
    for s in steps:
        chosen = next(o for o in s["options"] if o["effects"][-1] == s["added"])
        assert chosen["delta_bic"] <= FAST.delta_bic and chosen["delta_chi2"] < 0
        assert s["model"]["intervals"]["X1d"]["lower"] < s["model"]["parameters"]["X1d"]
    p, iv = r["final"]["parameters"], r["final"]["intervals"]
    assert iv["X2d"]["lower"] <= 0.5 <= iv["X2d"]["upper"] and iv["X2d"]["lower"] > 0
    assert abs(p["g"][0] / 0.4 - 1) < 0.1 and abs(p["tau_s"][0] / 0.3 - 1) < 0.1
    assert abs(p["X1d"] / 0.1 - 1) < 0.1
    assert r["final"]["skin"]["layers"][0]["X2"] == pytest.approx(p["X2d"])
    # the report shows each step: the table and one fitted curve per model of the chain
    paths = write_time_report(r, tmp_path)
    md = paths["md"].read_text()
    assert "effect by effect" in md and f"{VISCOELASTIC_CREEP}+{STIFF}" in md
    for curve in r["fit"].values():
        assert set(r["chain"]) <= set(curve["models"])
    assert paths["png"].stat().st_size > 0


def test_creep_alone_is_not_given_an_elastic_effect(space, tmp_path):
    skin = Skin.two_layer(0.1, 0.005, spectrum=Prony([0.4], [0.3]))
    r = diagnose_time_data(_skin_file(tmp_path / "creep.csv", skin, probes=(6.0,)), space,
                           FAST)
    assert r["effects"] == [VISCOELASTIC_CREEP], r["summary"]
    assert r["creep_terms"] == 1 and not r["removed"]
    # one aperture cannot tell which layer creeps, and says so
    assert not r["creep_layers"]["tested"] and "one probe" in r["creep_layers"]["reason"]
    assert "Which layer creeps: not tested" in r["summary"]


def test_two_probes_tell_that_the_hypodermis_creeps(space, tmp_path):
    skin = Skin.two_layer(0.08, 0.004, spectrum=Prony([1e-4], [0.3])).replace(
        {"hypodermis.spectrum.g[0]": 1.0, "hypodermis.spectrum.tau_s[0]": 0.5})
    r = diagnose_time_data(_skin_file(tmp_path / "h.csv", skin, probes=(2.0, 8.0)), space,
                           FAST)
    cl = r["creep_layers"]
    assert r["effects"] == [VISCOELASTIC_CREEP], r["summary"]
    assert cl["tested"] and cl["decisive"] and cl["creeping"] == "hypodermis", r["summary"]
    g, gd = cl["intervals"]["g_hypodermis"], cl["intervals"]["g_dermis"]
    assert g["lower"] <= 1.0 <= g["upper"]
    # the dermis is not shown to creep (its term may sit at tau's lower edge, where g
    # only trades with the instantaneous modulus and its interval opens)
    assert gd["lower"] < 0.05 and gd["estimate"] < 0.1 * g["estimate"]
    # each fit corrected by FE time solves, under the data's own model error
    assert cl["fe_correction"]["per_layer"]["applied"]
    assert cl["beta"]["2"] < 0.3 < 0.6 < cl["beta"]["8"]


# --------------------------------------------------------------------- the rule alone
class _Stub:
    """A fitter whose models have given chi^2 (the rule, without fits)."""

    def __init__(self, chi2: dict, n=1000):
        self.chi2, self.n, self.fitted = chi2, n, []

    def addable(self, effects):
        return [e for e in ("A", "B", "C") if e not in effects]

    def fit(self, effects, finish=True):  # no FE correction: nothing is held
        key = frozenset(effects)
        self.fitted.append(key)
        return TimeModel(tuple(effects), None, None, self.chi2[key], 2 + 2 * len(effects),
                         self.n)

    _cache = {}


def test_forward_selection_then_each_effect_checked_against_the_final_model():
    ln = np.log(1000)
    f = frozenset
    chi2 = {f(): 5000.0, f("A"): 3000.0, f("B"): 3500.0, f("C"): 3600.0,
            f("AB"): 2000.0, f("AC"): 2900.0, f("ABC"): 1000.0, f("BC"): 1500.0,
            f("AB"): 2000.0}
    sel = select_effects(_Stub(chi2), Settings())
    assert [s["added"] for s in sel["steps"]] == ["A", "B", "C"]
    assert sel["final"].effects == ("A", "B", "C") and sel["removed"] == []
    # B and C together explain what A did: A, added first, no longer earns its place
    chi2[f("BC")] = 1001.0
    sel = select_effects(_Stub(chi2), Settings())
    assert [r["effect"] for r in sel["removed"]] == ["A"]
    assert sel["final"].effects == ("B", "C") and sel["chain"][-1] is sel["final"]
    assert sel["removed"][0]["delta_bic_without"] == pytest.approx(-1.0 + 2 * ln)


def test_ties_and_a_model_that_fits_stop_the_selection():
    # both effects alone fit to the noise (chi^2 ~ n): tied at step 1, nothing added after
    chi2 = {frozenset(): 5000.0, frozenset("A"): 990.0, frozenset("B"): 992.0,
            frozenset("C"): 1500.0}
    stub = _Stub(chi2)
    sel = select_effects(stub, Settings())
    assert sel["steps"][0]["added"] == "A" and sel["steps"][0]["ambiguous_with"] == ["B"]
    assert len(sel["steps"]) == 1 and frozenset("AB") not in stub.fitted


def test_a_first_cycle_that_departs_is_described_not_fitted():
    from skinsuction.identify import TimeFitData

    t = np.arange(0, 9.0, 0.01)
    phase = np.where((t % 3.0) < 1.5, "on", "off").astype(object)
    d = np.where(phase == "on", 0.5, 0.1)
    rng = np.random.default_rng(0)
    meas = d + rng.normal(0, 0.002, t.size)
    data = TimeFitData("6 mm", 6.0, t, np.zeros_like(t), meas, np.full(t.size, 0.003),
                       phase, 0.002, 0.5, np.ones(t.size, bool))
    assert cycle_pattern([data], [d]) == []
    first = meas + np.where((t < 1.5), 0.02, 0.0)  # 20 µm more in the first hold
    data = TimeFitData("6 mm", 6.0, t, np.zeros_like(t), first, np.full(t.size, 0.003),
                       phase, 0.002, 0.5, np.ones(t.size, bool))
    (words,) = cycle_pattern([data], [d])
    assert "+20" in words and "preconditioning" in words


def test_the_second_creep_term_is_creeps_refinement_not_an_effect():
    from skinsuction.diagnose._time_effects import physical_effects

    assert physical_effects((VISCOELASTIC_CREEP, STIFF, CREEP_SECOND_TERM)) == [
        VISCOELASTIC_CREEP, STIFF]


def test_identify_fits_an_effect_with_the_spectrum(creep_and_stiffening, tmp_path, capsys):
    import json

    from skinsuction.cli import main

    out = tmp_path / "id"
    assert main(["identify", str(creep_and_stiffening.path), "--effect", STIFF, "--out",
                 str(out), "--repeats", "1"]) == 0
    assert "X2d = " in capsys.readouterr().out
    r = json.loads((out / "identification.json").read_text())
    iv = r["intervals"]["X2d"]
    assert r["model"]["effect"] == STIFF and iv["lower"] <= 0.5 <= iv["upper"]
    assert r["skin"]["layers"][0]["X2"] == pytest.approx(r["model"]["X2d"])
    assert r["settings"]["effect"] == STIFF
    # an effect the space has no rays for is refused by name
    assert main(["identify", str(creep_and_stiffening.path), "--effect", "nonsense",
                 "--out", str(tmp_path / "x")]) != 0
    assert "nonsense" in capsys.readouterr().err


def test_the_confusion_summary_counts_what_it_says():
    import pandas as pd

    from skinsuction.evaluation import effects_confusion_markdown, effects_confusion_summary

    base = {"design": "d", "error": None, "x1d": 0.1, "g": 0.5, "tau_s": 0.3,
            "x2_over_x1d": 5.0, "fit_x1d": 0.1, "fit_x2d": 0.55, "fit_g": 0.5,
            "fit_tau_s": 0.3, "diagnosis_cpu_s": 1.0, "layers_tested": False,
            "creep_layer": "both", "creeping": None}
    rows = [
        # a pair named whole
        {**base, "truth": f"{VISCOELASTIC_CREEP}+{STIFF}", "named": f"{VISCOELASTIC_CREEP},{STIFF}",
         "ambiguous_with": "", f"detectable_{VISCOELASTIC_CREEP}": True,
         f"detectable_{STIFF}": True},
        # a pair whose stiffening was named pre-tension, tied: wrong but tied
        {**base, "truth": f"{VISCOELASTIC_CREEP}+{STIFF}",
         "named": f"{VISCOELASTIC_CREEP},pre_tension", "ambiguous_with": STIFF,
         f"detectable_{VISCOELASTIC_CREEP}": True, f"detectable_{STIFF}": True},
        # creep named with a wrong thickness, not tied
        {**base, "truth": VISCOELASTIC_CREEP, "named": f"{VISCOELASTIC_CREEP},dermis_thickness",
         "ambiguous_with": "", f"detectable_{VISCOELASTIC_CREEP}": True},
        # an elastic draw given creep
        {**base, "truth": "none", "named": VISCOELASTIC_CREEP, "ambiguous_with": ""},
        # a failed FE solve: counted as failed, not dropped
        {**base, "truth": "none", "error": "RuntimeError: FE stopped"},
    ]
    s = effects_confusion_summary(pd.DataFrame(rows))
    d = s["d"]
    assert s["failed"] == 1 and d["draws"] == 4
    assert d["effects"][VISCOELASTIC_CREEP] == {"with_effect": 3, "detectable": 3, "named": 3,
                                                "right_or_tied": 3}
    assert d["effects"][STIFF] == {"with_effect": 2, "detectable": 2, "named": 1,
                                   "right_or_tied": 2}
    assert d["pairs"] == [1, 2] and d["false_effect"] == [1, 1]
    assert d["wrong_not_tied"] == [1, 3]
    assert d["median_error_pct"]["X2d"] == [pytest.approx(10.0), 1]
    assert "| strain_stiffening | 2/2 | 1/2 | 2/2 |" in effects_confusion_markdown(
        pd.DataFrame(rows))


def test_a_study_names_both_effects_of_a_mode1_file(creep_and_stiffening, tmp_path):
    import shutil

    import pandas as pd

    from skinsuction.cli import main

    folder = tmp_path / "study"
    folder.mkdir()
    shutil.copy(creep_and_stiffening.path, folder / "pair.csv")
    out = tmp_path / "out"
    assert main(["study", str(folder), "--out", str(out), "--repeats", "1"]) == 0
    (row,) = pd.read_parquet(out / "curves.parquet").to_dict("records")
    assert row["effects"] == f"{VISCOELASTIC_CREEP},{STIFF}", row["warnings"]
    assert row["cause"] == VISCOELASTIC_CREEP and row["extra_parameter"] == "X2d"
    assert row["extra_lower"] <= 0.5 <= row["extra_upper"]


def test_a_diagnosis_takes_the_identifications_creep_fit(space, creep_and_stiffening,
                                                        monkeypatch):
    """A study identifies then diagnoses each curve: the diagnosis's creep model is the
    identification's FE-corrected fit (two FE time solves per curve fewer), so its
    creep parameters are the identification's; the effects named are the same as a
    diagnosis fitting creep itself (test above: creep and stiffening, X2d's interval
    over the truth); a fit of other weights is not taken."""
    import dataclasses

    import skinsuction.identify._time_correction as tc
    from skinsuction.identify.time_curves import identify_time_data

    ident = identify_time_data(creep_and_stiffening, space, repeats=1, seed=0)
    assert ident.fitted.fits(prepare_time_fit(creep_and_stiffening, space)["data"], 1, 2,
                             geometry=ident.fitted.geometry)
    assert "fitted" not in ident.to_json()
    solves, solve = [], tc.fe_time_curve
    monkeypatch.setattr(tc, "fe_time_curve",
                        lambda skin, d, mesh=None: solves.append(d.label) or solve(skin, d, mesh))
    r = diagnose_time_data(creep_and_stiffening, space, FAST, creep=ident.fitted)
    creep = r["viscoelastic"]
    assert creep["fe_correction"]["reused"] and creep["chi2"] == pytest.approx(
        ident.fit_quality["chi2"])
    assert creep["parameters"]["g"] == pytest.approx(ident.g)
    options = [o for s in r["steps"] for o in s["options"] if o["fast_path_chi2"] is not None]
    finished = [o for o in options if o["fe_correction_from"] and not o["fe_correction_held"]]
    layer_fits = (r["creep_layers"].get("fe_correction") or {}).values()
    per_layer = sum(bool(f.get("applied")) for f in layer_fits)
    assert len(solves) == 2 * (len(finished) + 2 * per_layer)  # none for creep's own fit
    assert r["effects"] == [VISCOELASTIC_CREEP, STIFF], r["summary"]
    iv = r["final"]["intervals"]["X2d"]
    assert iv["lower"] <= 0.5 <= iv["upper"]
    # another noise (other weights) or other steps: not the same fit, creep is fitted
    other = dataclasses.replace(FAST, noise_um=7.0)
    for settings in (other, dataclasses.replace(FAST, fe_correction=1)):
        prep = prepare_time_fit(creep_and_stiffening, space, noise_um=settings.noise_um)
        fitter = EffectFitter(prep, settings, [], creep=ident.fitted)
        assert not fitter._cache
    assert EffectFitter(prepare_time_fit(creep_and_stiffening, space), FAST, [],
                        creep=ident.fitted)._cache


def test_a_stopped_fe_correction_keeps_the_fast_fit_and_says_so(space, tmp_path, monkeypatch):
    import skinsuction.identify._time_correction as tc

    def stops(skin, data, mesh=None):
        raise RuntimeError(f"{data.label}: the FE time solve stopped: no equilibrium")

    monkeypatch.setattr(tc, "fe_time_curve", stops)
    skin = Skin.two_layer(0.1, 0.005, spectrum=Prony([0.4], [0.3]))
    r = diagnose_time_data(_skin_file(tmp_path / "c.csv", skin, probes=(6.0,)), space, FAST)
    assert r["effects"] == [VISCOELASTIC_CREEP], r["summary"]
    assert r["viscoelastic"]["fe_correction"]["applied"] is False
    assert any(w.startswith("FE correction: viscoelastic_creep") and "stopped" in w
               for w in r["warnings"]), r["warnings"]


def test_the_face_protocol_in_the_load_tail_gets_creep_and_stiffening(space):
    """Issue 35's face skin (2 mm, 450 mbar mode 1, X1d 0.018 MPa: p/X1d = 25 000, in the
    space's load tail; data/make_example_face.py): before the tail X1d sat at the space's
    edge (450 / 2·10⁴ = 0.0225 MPa) and the verdict was beyond_space."""
    from pathlib import Path

    data = load_time_curves(Path(__file__).resolve().parents[1] / "data"
                            / "example_face_mode1.csv")
    r = diagnose_time_data(data, space, FAST)
    assert r["effects"] == [VISCOELASTIC_CREEP, STIFF], r["summary"]
    assert r["verdict"] == "cause_found" and not r["beyond_space"]
    p, iv = r["final"]["parameters"], r["final"]["intervals"]
    assert 450.0 / p["X1d"] > 20000.0  # read in the tail
    assert abs(p["X1d"] / 0.018 - 1) < 0.05
    assert iv["X2d"]["lower"] <= 0.1 <= iv["X2d"]["upper"]
