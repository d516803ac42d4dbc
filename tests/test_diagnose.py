"""The diagnosis without FE runs: statistics, ray spaces, fits, verdict, report, CLI.

The ray spaces here are analytic stand-ins (a made-up two-layer curve family
that obeys the scaling law), so every test runs in seconds; the hidden-effect
tests with FE-made virtual experiments are in test_diagnose_hidden.py.
"""

import argparse
import json
import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from skinsuction.commands.diagnose import add_arguments
from skinsuction.diagnose import BASELINE, Cause, FitData, Settings, bic, default_registry, diagnose, fit_model, misfit_test, noise_from_differences, noise_from_replicates, registry_from_config, write_report
from skinsuction.space import RayInterpolant, RaySpace, RaySpec, SpaceMissingError, parse_ray_id, ray_id, rays_of, read_ray_space, read_ray_spaces
from skinsuction.space import RAY_ID_PATTERN, ray_bundles
from skinsuction.space._storage import _write_parquet
from skinsuction.diagnose._stats import describe_residuals, difference_weights
from skinsuction.identify import window_focusing
from skinsuction.measured import load_measured

ROOT = Path(__file__).resolve().parents[1]


# ------------------------------------------------------------ window focusing, d = 3
class Bowl:
    """A 3-D quadratic bowl with its minimum at (0.3, -0.2, 0.7)."""

    lower, upper = np.zeros(3) - 1, np.ones(3)
    error_unit = "1"
    centre = np.array([0.3, -0.2, 0.7])

    def __call__(self, x):
        return ((x - self.centre) ** 2 * [1, 10, 100]).sum(axis=1)

    def error(self, cost):
        return math.sqrt(cost)


def test_window_focusing_finds_a_3d_minimum():
    r = window_focusing(Bowl(), seed=0, n_samples=500, n_best=10, tolerance=1e-9)
    assert r.estimate.shape == (3,)
    np.testing.assert_allclose(r.estimate, Bowl.centre, atol=1e-3)
    assert all(lo.shape == (3,) for lo, _ in r.windows)


# ------------------------------------------------------------------ noise estimate
def test_difference_weights_annihilate_quadratics_on_uneven_steps():
    x = np.array([0.0, 1.0, 3.0, 3.5, 7.0, 9.0])
    c = difference_weights(x, order=3)
    assert c.shape == (3, 4)
    np.testing.assert_allclose(np.linalg.norm(c, axis=1), 1.0)
    for t in range(3):
        xs = x[t:t + 4]
        for poly in (np.ones_like(xs), xs, xs ** 2 - 3 * xs):
            assert abs(c[t] @ poly) < 1e-9
        assert abs(c[t] @ xs ** 3) > 1e-3


def test_noise_from_differences_is_unbiased_and_its_dof_is_right():
    p = np.arange(2.0, 101.0, 2.0)
    smooth = 0.8 * (1 - np.exp(-p / 40))  # mm, a curved suction curve
    rng = np.random.default_rng(0)
    est = [noise_from_differences([(p, smooth + rng.normal(0, 2e-3, p.size)),
                                   (p, 0.3 * smooth + rng.normal(0, 2e-3, p.size))])
           for _ in range(400)]
    sd = np.array([e.sd_um for e in est])
    assert sd.mean() == pytest.approx(2.0, rel=0.03)
    # the spread of the estimate matches the effective dof: sd(s)/s ~ 1/sqrt(2 dof)
    assert sd.std() / sd.mean() == pytest.approx(1 / math.sqrt(2 * est[0].dof), rel=0.2)
    assert noise_from_differences([(p, smooth)]).sd_um < 0.01  # the curve itself is removed


def test_noise_dof_is_the_dense_formula_on_uneven_steps():
    """The banded ||C C^T||_F^2 (and so the dof) equals the one of the full difference
    matrix, and the weights span the null space that an SVD of the window's
    Vandermonde matrix finds."""
    from skinsuction.noise import difference_weights

    rng = np.random.default_rng(7)
    p = np.cumsum(rng.uniform(0.2, 3.0, 60))
    c = difference_weights(p, 3)
    for t in (0, 17, 56):
        xs = p[t:t + 4]
        _, _, vt = np.linalg.svd(np.vander(xs - xs.mean(), 3, increasing=True).T)
        assert abs(abs(vt[-1] @ c[t]) - 1.0) < 1e-9
    full = np.zeros((len(c), p.size))
    np.put_along_axis(full, np.arange(len(c))[:, None] + np.arange(4), c, axis=1)
    dense = len(c) ** 2 / float(((full @ full.T) ** 2).sum())
    est = noise_from_differences([(p, np.sqrt(p))])
    assert est.dof == pytest.approx(dense, rel=1e-12)


def test_noise_from_replicates_pools_the_scatter():
    rng = np.random.default_rng(1)
    curve = np.linspace(0, 1, 40)
    groups = [curve + rng.normal(0, 3e-3, (3, 40)), curve + rng.normal(0, 3e-3, (5, 40))]
    est = noise_from_replicates(groups)
    assert est.method == "replicates" and est.dof == 40 * 2 + 40 * 4
    assert est.sd_um == pytest.approx(3.0, rel=0.1)
    with pytest.raises(ValueError, match="two or more"):
        noise_from_replicates([curve[None, :]])


# ------------------------------------------------------------------ misfit test
def test_misfit_test_false_alarm_rate_is_alpha_and_it_sees_a_pattern():
    rng = np.random.default_rng(2)
    p = np.arange(2.0, 101.0, 2.0)
    alarms = 0
    for _ in range(400):
        res = {6.0: (p, rng.normal(0, 2.0, p.size)), 2.0: (p, rng.normal(0, 2.0, p.size))}
        alarms += misfit_test(res, {6.0: 2.0, 2.0: 2.0}, math.inf, alpha=0.05).significant
    assert 0.02 < alarms / 400 < 0.09
    arch = 3.0 * np.sin(np.pi * p / 100)  # 1.5 noise sd, concave
    res = {6.0: (p, arch + rng.normal(0, 2.0, p.size))}
    t = misfit_test(res, {6.0: 2.0}, 40.0)
    assert t.significant and t.p_value < 1e-4
    text = describe_residuals(t, res, {6.0: 2.0})
    assert "6 mm probe" in text and "concave" in text and "too little deflection" in text


def test_bic_charges_ln_n_per_parameter():
    assert bic(100.0, 3, 100) - bic(100.0, 2, 100) == pytest.approx(math.log(100))


# ------------------------------------------------------------------ causes and ids
def test_registry_of_the_configs_is_valid():
    for name in ("config", "ci"):
        cfg = yaml.safe_load((ROOT / "config" / f"{name}.yaml").read_text())
        reg = registry_from_config(cfg["scale_free_space"]["causes"])
        assert {"strain_stiffening", "dermis_thickness", "pre_tension"} <= set(reg)
        for c in reg.values():
            assert c.neutral in c.nodes
    reg = default_registry()
    assert reg["strain_stiffening"].value(4.0, 0.03) == pytest.approx(0.12)
    assert reg["pre_tension"].simulate_keywords(1.06, 0.03) == {"prestretch": 1.06}


def test_a_cause_needs_its_neutral_value_among_the_nodes():
    with pytest.raises(ValueError, match="neutral value"):
        Cause("x", "t_d", "t_d", "mm", False, 1.0, (1.5, 2.0))
    with pytest.raises(ValueError, match="reserved"):
        Cause("none", "t_d", "t_d", "mm", False, 1.0, (1.0, 2.0))


def test_ray_ids_round_trip_and_match_the_wildcard():
    import re

    params = dict(probe_mm=6, bottom="fixed", x1d=0.02, x1h=2e-4, x2d=0.08, prestretch=1.06)
    rid = ray_id(params)
    assert rid.endswith("__prestretch=1.06") and re.fullmatch(RAY_ID_PATTERN, rid)
    back = parse_ray_id(rid)
    assert back["prestretch"] == 1.06 and back["x2d"] == 0.08 and back["probe_mm"] == 6
    assert "__" not in ray_id(dict(params, prestretch=1.0))  # neutral: plain point id


def test_rays_of_a_cause_share_the_neo_hookean_rays():
    spec = RaySpec([2, 6], [0.01, 0.1], load_max=5000, load_steps=4)
    reg = default_registry()
    base = {r["ray_id"] for r in rays_of(spec)}
    for cause in reg.values():
        ids = {r["ray_id"] for r in rays_of(spec, cause)}
        assert base <= ids and len(ids) == 2 * 2 * len(cause.nodes)


# ------------------------------------------------------------- analytic ray spaces
def toy_curve(x1d, r, c, p, probe, kind):
    """A made-up smooth family with the scaling law: depends on p / X1d, r and c."""
    q = p / (1e4 * x1d)  # p in mbar, X1d in MPa
    # the hypodermis matters more under the wide probe, as in the FE model
    soft = 0.4 * (1 + 0.2 / (r + 0.02)) if probe == 6 else 0.1 * (1 + 0.01 / (r + 0.02))
    m = soft * q / (1 + 0.3 * soft * q)
    if kind == "strain_stiffening":
        m = m / (1 + 0.05 * c * m ** 2)
    elif kind == "pre_tension":
        m = m / (1 + 0.5 * (c - 1) / (0.02 + m))
    return m


def toy_spaces(ratio_nodes=np.geomspace(0.005, 0.5, 9), kinds=("strain_stiffening",
                                                                  "pre_tension")):
    # rays at X1d = 0.02 MPa to 100 mbar: p/X1d up to 5000 mbar/MPa in 20 steps
    spec = RaySpec([2, 6], ratio_nodes, load_max=5000, load_steps=20, x1d_range=(0.02, 0.2),
                   x1d_ref=0.02)
    reg = default_registry()
    p = np.asarray(spec.pressures_mbar)
    spaces = {}
    for kind in (BASELINE, *kinds):
        cause = reg.get(kind)
        coords = np.array(cause.nodes if cause else [np.nan])
        arrays = {}
        for probe in spec.probes_mm:
            a = np.empty((len(spec.ratio_nodes), coords.size, p.size))
            for i, r in enumerate(spec.ratio_nodes):
                for j, c in enumerate(coords):
                    a[i, j] = toy_curve(spec.x1d_ref, r, c, p, probe, kind)
            arrays[probe] = a
        spaces[kind] = RaySpace(cause, spec, coords, arrays, {})
    return spaces


def test_ray_interpolant_is_exact_at_nodes_and_follows_the_scaling_law():
    spaces = toy_spaces()
    s = spaces["strain_stiffening"]
    p = np.arange(5.0, 101.0, 5.0)
    f = RayInterpolant(s, 6.0, p)
    r, c = s.spec.ratio_nodes[3], s.coordinates[2]
    u = s.cause.to_axis(c)  # the fit's coordinate: log10(1 + X2d/X1d)
    # at X1d_ref the candidate reads its ray at the ray's own pressures
    got = f([[math.log10(0.02), math.log10(r), u]])[0]
    np.testing.assert_allclose(got, toy_curve(0.02, r, c, p, 6, "strain_stiffening"), rtol=1e-12)
    # X1d = 2 X1d_ref reads the ray at p / 2 (nodes at 2.5 mbar steps are not all rays' nodes,
    # so compare with the family, to the accuracy of the interpolation)
    got = f([[math.log10(0.04), math.log10(r), u]])[0]
    np.testing.assert_allclose(got, toy_curve(0.04, r, c, p, 6, "strain_stiffening"), rtol=2e-4)
    # beyond the load reach (p/X1d > 5000 at 100 mbar) and outside the ratio range: NaN
    assert np.isnan(f([[math.log10(0.019), math.log10(r), u]])[0, -1])
    assert np.isnan(f([[math.log10(0.03), math.log10(0.6), u]])).all()
    assert f.lower[0] == pytest.approx(math.log10(0.02))  # 100 mbar / 5000 mbar/MPa


def test_any_pressure_protocol_within_the_reach_of_the_space():
    s = toy_spaces()["neo_hookean"]
    # 300 mbar in 7.5 mbar steps, no 0 row: X1d from 300 / 5000 = 0.06 MPa up
    p = np.arange(7.5, 300.1, 7.5)
    f = RayInterpolant(s, 6.0, p)
    assert f.lower[0] == pytest.approx(math.log10(0.06))
    r = s.spec.ratio_nodes[4]
    got = f([[math.log10(0.1), math.log10(r)]])[0]
    np.testing.assert_allclose(got, toy_curve(0.1, r, 0, p, 6, BASELINE), rtol=2e-4)
    # beyond the reach of the whole X1d window: a clear error naming the keys
    with pytest.raises(ValueError, match="load.max"):
        RayInterpolant(s, 6.0, [0, 2000.0])


def test_a_stopped_ray_is_avoided_by_shifting_the_stencil():
    s = toy_spaces()["strain_stiffening"]  # coordinates 0, 1, 3, 10, 30, ...
    p = np.arange(5.0, 101.0, 5.0)
    r, c = math.sqrt(s.spec.ratio_nodes[3] * s.spec.ratio_nodes[4]), 2.0  # cell (1, 3)
    theta = [[math.log10(0.02), math.log10(r), s.cause.to_axis(c)]]
    exact = toy_curve(0.02, r, c, p, 6, "strain_stiffening")
    before = RayInterpolant(s, 6.0, p)(theta)[0]
    rays = {q: a.copy() for q, a in s.deflection_mm.items()}
    rays[6.0][:, 0, 12:] = np.nan  # the rays at X2d = 0 stopped at 55 mbar
    stopped = RaySpace(s.cause, s.spec, s.coordinates, rays, {})
    after = RayInterpolant(stopped, 6.0, p)(theta)[0]
    assert np.all(np.isfinite(after))
    np.testing.assert_allclose(after[:11], before[:11], rtol=1e-12)  # centred stencil
    np.testing.assert_allclose(after, exact, rtol=2e-3)  # shifted stencil beyond 55 mbar
    # on the stopped node itself there is nothing to shift to
    on_node = [[math.log10(0.02), math.log10(r), 0.0]]
    assert np.isnan(RayInterpolant(stopped, 6.0, p)(on_node)[0, 11:]).all()


def test_rays_combined_to_the_last_load_read_are_the_full_rays_cut_there():
    s = toy_spaces()["strain_stiffening"]
    rays = {q: a.copy() for q, a in s.deflection_mm.items()}
    rays[6.0][:, 0, 12:] = np.nan  # stopped rays send candidates to the shifted stencils
    s = RaySpace(s.cause, s.spec, s.coordinates, rays, {})
    rng = np.random.default_rng(5)
    p = np.arange(0.0, 101.0, 2.0)
    f = RayInterpolant(s, 6.0, p)
    n = 500
    theta = np.column_stack([rng.uniform(f.lower[0], f.upper[0], n),
                             rng.uniform(f.lower[1], f.upper[1], n),
                             rng.uniform(f.lower[2], f.upper[2], n)])
    full = f.combined_rays(theta)
    for loads in (2, 7, 13, full.shape[1]):
        np.testing.assert_array_equal(f.combined_rays(theta, loads=loads), full[:, :loads])
    # the measured curves read off the cut rays are those read off the full ones, bit
    # for bit, for a wide batch and for a focused stiff one (which reads few loads)
    cut = RayInterpolant.combined_rays
    for batch in (theta, theta[theta[:, 0] > f.upper[0] - 0.2]):
        got = f(batch)
        try:
            RayInterpolant.combined_rays = lambda self, t, loads=None: cut(self, t)
            want = f(batch)
        finally:
            RayInterpolant.combined_rays = cut
        np.testing.assert_array_equal(got, want)
        assert np.isfinite(got).sum() > 0.5 * got.size


def test_curves_read_at_once_are_each_interpolants_own_bit_for_bit():
    # a fit with a given thickness reads its model and the brackets at the same X1d:
    # their load cells are found once, the values are each interpolant's own
    from skinsuction.space import read_at_once

    spaces = toy_spaces()
    s = spaces["strain_stiffening"]
    rays = {q: a.copy() for q, a in s.deflection_mm.items()}
    rays[6.0][:, 0, 12:] = np.nan  # stopped rays: the rules of read() too
    stopped = RaySpace(s.cause, s.spec, s.coordinates, rays, {})
    p = np.arange(0.0, 101.0, 2.0)
    f3, g3 = RayInterpolant(s, 6.0, p), RayInterpolant(stopped, 6.0, p)
    f2 = RayInterpolant(spaces["neo_hookean"], 6.0, p)
    other = RayInterpolant(spaces["neo_hookean"], 6.0, p[:20])  # other pressures
    rng = np.random.default_rng(2)
    theta = np.column_stack([rng.uniform(f3.lower[0], f3.upper[0], 300),
                             rng.uniform(f3.lower[1], f3.upper[1], 300),
                             rng.uniform(f3.lower[2], f3.upper[2], 300)])
    calls = [(f3, theta), (g3, theta), (f2, theta[:, :2]), (other, theta[:, :2])]
    got = read_at_once(calls)
    for (f, t), m in zip(calls, got, strict=True):
        np.testing.assert_array_equal(m, f(t))
    assert got[3].shape == (300, 20)
    assert np.isfinite(got[1]).sum() > 0.5 * got[1].size


def test_ray_space_round_trips_through_parquet(tmp_path):
    s = toy_spaces()["pre_tension"]
    s.metadata = {"ray_spec": s.spec.to_dict(), "cause": s.cause.to_dict()}
    _write_parquet(s.frame(), tmp_path / "pre_tension.parquet", s.metadata)
    back = read_ray_space(tmp_path / "pre_tension.parquet")
    assert back.cause == s.cause and back.spec == s.spec
    for probe in (2.0, 6.0):
        np.testing.assert_array_equal(back.rays(probe), s.rays(probe))
    with pytest.raises(SpaceMissingError, match="neo_hookean"):
        read_ray_spaces(tmp_path)
    with pytest.raises(SpaceMissingError, match="snakemake"):
        read_ray_spaces(tmp_path / "nowhere")


def _toy_data(x1d, r, c, kind, noise_um, seed, probes=(2.0, 6.0)):
    from skinsuction.measured import MeasuredCurve, MeasuredData

    rng = np.random.default_rng(seed)
    p = np.arange(0.0, 101.0, 2.0)
    curves = []
    for probe in probes:
        m = toy_curve(x1d, r, c, p, probe, kind) + rng.normal(0, 1e-3 * noise_um, p.size)
        m[0] = 0.0
        curves.append(MeasuredCurve(probe, p, m, "", 1))
    return MeasuredData("toy.csv", tuple(curves), {}, ())


def test_fit_recovers_three_parameters_of_the_toy_family():
    spaces = toy_spaces()
    data = _toy_data(0.03, 0.02, 8.0, "strain_stiffening", 0.0, 0)
    fd = {c.probe_mm: FitData(c.probe_mm, c.pressure_mbar[1:], c.deflection_mm[1:], 1.0)
          for c in data.curves}
    f = fit_model(spaces["strain_stiffening"], fd, seed=0, repeats=1)
    assert f.parameters["X1d"] == pytest.approx(0.03, rel=1e-3)
    assert f.parameters["X1h"] == pytest.approx(0.0006, rel=1e-2)
    assert f.parameters["X2d"] == pytest.approx(0.24, rel=1e-2)
    assert f.rms_um < 0.05


def test_the_space_error_term_is_the_chi2_of_its_covariance_in_every_fit_path():
    # with_space_error must give the chi^2 r^T (s^2 I + v v^T)^-1 r of the measured
    # profile (computed here by a dense solve) in the window focusing's objective, the
    # least-squares residuals and the reported fit alike
    from skinsuction.diagnose._fit import ModelCurves, _Objective, evaluate_fit, with_space_error
    from skinsuction.identify.measured_fit import (DISCRETISATION_ERROR_HEIGHTS,
                                                   DISCRETISATION_ERROR_RMS, SPACE_ERROR_LOADS,
                                                   SPACE_ERROR_RMS)

    spaces = toy_spaces()
    data = _toy_data(0.02, 0.02, None, "none", 1.0, 4, probes=(6.0,))
    c = data.curves[0]
    fd = {6.0: FitData(6.0, c.pressure_mbar[1:], c.deflection_mm[1:], 1.0)}
    weighted = with_space_error(fd, 0.02)
    theta = np.array([math.log10(0.021), math.log10(0.02)])  # off the truth: a bias
    model = ModelCurves(spaces[BASELINE], weighted)
    fit = evaluate_fit(model, theta, BASELINE)
    r = 1e3 * (fd[6.0].deflection_mm - fit.fitted_mm[6.0])  # µm
    # the space's error at each load and the discretisation's at each dome height M/a,
    # the latter also in each point's own sd (noise 1 µm)
    m = np.abs(fd[6.0].deflection_mm)
    disc = np.interp(m / 3.0, DISCRETISATION_ERROR_HEIGHTS, DISCRETISATION_ERROR_RMS[6.0])
    v = 1e3 * np.hypot(np.interp(fd[6.0].pressure_mbar / 0.02, SPACE_ERROR_LOADS,
                                 SPACE_ERROR_RMS[6.0]), disc) * m
    cov = np.diag(1.0 + (1e3 * disc * m) ** 2) + np.outer(v, v)
    dense = float(r @ np.linalg.solve(cov, r))
    assert fit.chi2 == pytest.approx(dense, rel=1e-10)
    obj = _Objective(model)
    assert 2 * obj(theta[None, :])[0] == pytest.approx(dense, rel=1e-10)
    assert (obj.residuals(theta) ** 2).sum() == pytest.approx(dense, rel=1e-10)
    plain = evaluate_fit(ModelCurves(spaces[BASELINE], fd), theta, BASELINE)
    assert plain.chi2 == pytest.approx((r ** 2).sum(), rel=1e-10) and plain.chi2 > fit.chi2


def test_a_smooth_error_of_the_space_is_not_read_as_a_misfit():
    # soft skin under the 6 mm probe: the space's own error (smooth, growing with the
    # load) added to a neo-Hookean curve is a "pattern" to the plain test, not with the term
    from skinsuction.identify.measured_fit import SPACE_ERROR_LOADS, SPACE_ERROR_RMS
    from skinsuction.measured import MeasuredCurve, MeasuredData

    spaces = toy_spaces()
    p = np.arange(0.0, 101.0, 2.0)
    x1d = 0.02
    m = toy_curve(x1d, 0.02, None, p, 6.0, "none")
    # 2.5 times the measured rms, along its profile (well within what FE runs show)
    bias = 2.5 * np.interp(p / x1d, SPACE_ERROR_LOADS, SPACE_ERROR_RMS[6.0]) * m
    noisy = m + bias + np.random.default_rng(5).normal(0, 0.1e-3, p.size)
    noisy[0] = 0.0
    data = MeasuredData("soft.csv", (MeasuredCurve(6.0, p, noisy, "", 1),), {}, ())
    fast = dict(repeats=1, noise_um=0.1, window_focusing={"n_samples": 400, "n_best": 10,
                                                         "tolerance": 1e-6, "max_iter": 100})
    plain = diagnose(data, spaces, Settings(space_error=False, **fast))
    weighed = diagnose(data, spaces, Settings(**fast))
    assert plain["baseline"]["systematic_misfit"], plain["summary"]
    assert not weighed["baseline"]["systematic_misfit"], weighed["summary"]
    assert weighed["cause"] == "none"


@pytest.mark.parametrize("kind,coord", [("none", None), ("strain_stiffening", 16.0),
                                        ("pre_tension", 1.09)])
def test_toy_diagnosis_names_the_hidden_cause(kind, coord, tmp_path):
    spaces = toy_spaces()
    data = _toy_data(0.03, 0.02, coord, kind, 2.0, 3)
    fast = Settings(repeats=1, window_focusing={"n_samples": 400, "n_best": 10,
                                                "tolerance": 1e-6, "max_iter": 100})
    report = diagnose(data, spaces, fast, source={"file": "toy.csv", "sha256": "0"})
    assert report["cause"] == kind, report["summary"]
    assert report["baseline"]["systematic_misfit"] == (kind != "none")
    if kind != "none":
        assert report["gain"]["delta_bic"] <= -10 and report["gain"]["E_ratio"] < 1
    paths = write_report(report, tmp_path)
    back = json.loads(paths["json"].read_text())  # strict JSON: no NaN
    assert back["cause"] == kind and back["input"]["probes_mm"] == [2.0, 6.0]
    assert {"input", "noise_um", "baseline", "candidates", "cause", "extended", "gain"} <= set(back)
    for c in back["candidates"]:
        assert {"cause", "parameters", "E_um", "delta_bic", "holdout_E_um"} <= set(c)
    md = paths["md"].read_text()
    assert f"Cause: `{kind}`" in md.replace("**", "")
    # the rule stated in the report is the rule applied (no pattern gate by default)
    assert "need not show a pattern first" in md and back["detection"]["candidate_bic"] == (
        kind != "none")
    for name in ("fit", "residuals", "gain"):
        assert paths[f"{name}_png"].stat().st_size > 1000


@pytest.mark.parametrize("x1d,kind,coord,parameter,side,key", [
    (0.012, "none", None, "X1d", "lower", "scale_free_space.x1d_mpa.min"),
    (0.03, "pre_tension", 1.4, "lambda0", "upper", "scale_free_space.causes.pre_tension.nodes"),
])
def test_a_fit_at_the_edge_of_the_space_is_beyond_space_never_none(x1d, kind, coord,
                                                                    parameter, side, key):
    spaces = toy_spaces()  # X1d window 0.02..0.2 MPa, lambda0 up to 1.25
    data = _toy_data(x1d, 0.02, coord, kind, 1.0, 5)
    fast = Settings(repeats=1, holdout=False,
                    window_focusing={"n_samples": 400, "n_best": 10, "tolerance": 1e-6,
                                     "max_iter": 100})
    report = diagnose(data, spaces, fast)
    assert report["verdict"] == "beyond_space", report["summary"]
    assert report["cause"] != "none"
    hits = [f for f in report["beyond_space"] if f["parameter"] == parameter]
    assert hits and hits[0]["side"] == side and hits[0]["config_key"] == key
    assert "BEYOND THE SIMULATED SPACE" in report["summary"] and key in report["summary"]


def test_a_fit_inside_the_space_is_not_flagged():
    report = diagnose(_toy_data(0.05, 0.02, None, "none", 1.0, 6), toy_spaces(),
                      Settings(repeats=1, holdout=False))
    assert report["verdict"] == "neo_hookean_fits" and report["beyond_space"] == []
    assert not any(f["at_bound"] for f in report["baseline"]["at_bound"].values())


def test_leaving_the_holdout_out_changes_no_fit():
    # the holdout is no part of the decision; the detectability draws leave it out
    # (a third of their cost) and must measure the diagnosis users get with it
    spaces = toy_spaces()
    data = _toy_data(0.03, 0.02, 1.09, "pre_tension", 2.0, 3)
    fast = {"repeats": 1, "window_focusing": {"n_samples": 300, "n_best": 10,
                                              "tolerance": 1e-6, "max_iter": 60}}
    with_it = diagnose(data, spaces, Settings(**fast))
    without = diagnose(data, spaces, Settings(**fast, holdout=False))
    assert with_it["baseline"]["holdout_E_um"] is not None
    assert without["baseline"]["holdout_E_um"] is None
    assert with_it["cause"] == without["cause"] == "pre_tension"
    assert with_it["verdict"] == without["verdict"]
    for a, b in zip(with_it["candidates"], without["candidates"], strict=True):
        assert a["cause"] == b["cause"] and a["parameters"] == b["parameters"]
        assert a["delta_bic"] == b["delta_bic"]
    assert with_it["baseline"]["parameters"] == without["baseline"]["parameters"]


def test_a_studys_diagnosis_leaves_the_baselines_intervals_to_the_identification():
    # a study's row takes X1d, X1h and their intervals from the identification: the
    # diagnosis computes the chosen cause's alone, and decides as with every interval
    spaces = toy_spaces()
    data = _toy_data(0.03, 0.02, 1.09, "pre_tension", 2.0, 3)
    fast = {"repeats": 1, "holdout": False,
            "window_focusing": {"n_samples": 300, "n_best": 10, "tolerance": 1e-6,
                                "max_iter": 60}}
    full = diagnose(data, spaces, Settings(**fast))
    study = diagnose(data, spaces, Settings(**fast, intervals="cause"))
    assert full["baseline"]["intervals"]["X1d"]["lower"] > 0
    assert study["baseline"]["intervals"] is None
    assert study["cause"] == full["cause"] == "pre_tension"
    assert study["verdict"] == full["verdict"]
    chosen = [next(c for c in r["candidates"] if c["cause"] == "pre_tension")
              for r in (full, study)]
    assert chosen[1]["intervals"] == chosen[0]["intervals"]
    assert chosen[1]["intervals"]["lambda0"]["lower"] < 1.09 < chosen[1]["intervals"]["lambda0"]["upper"]
    with pytest.raises(ValueError, match="'chosen', 'all' or 'cause'"):
        Settings(intervals="none")


def test_one_probe_only_has_no_holdout():
    spaces = toy_spaces(kinds=("strain_stiffening",))
    data = _toy_data(0.03, 0.02, None, "none", 2.0, 4, probes=(6.0,))
    report = diagnose(data, spaces, Settings(repeats=1))
    assert report["input"]["probes_mm"] == [6.0]
    assert all(c["holdout_E_um"] is None for c in report["candidates"])
    assert report["cause"] == "none" and report["gain"] is None


# ------------------------------------------------------------------ CLI function
def test_command_without_spaces_says_how_to_build_them(tmp_path):
    from skinsuction.commands.diagnose import run as command
    from skinsuction.identify.measured_fit import InputError

    csv = tmp_path / "m.csv"
    csv.write_text("probe_mm,pressure_mbar,deflection_mm\n6,0,0\n6,50,0.3\n6,100,0.5\n")
    parser = argparse.ArgumentParser()
    add_arguments(parser)
    args = parser.parse_args([str(csv), "--out", str(tmp_path / "out"),
                              "--space-dir", str(tmp_path / "missing")])
    with pytest.raises(InputError, match="scale_free_space"):
        command(args)
    with pytest.raises(SystemExit):
        parser.parse_args([str(csv), "--out", "o", "--delta-bic", "3"])
    bad = tmp_path / "spaces"
    bad.mkdir()
    (bad / "neo_hookean.parquet").write_text("not parquet")
    args.space_dir = str(bad)
    with pytest.raises(InputError, match="not a scale-free space"):
        command(args)


def test_measured_loader_is_shared_with_identify(tmp_path):
    csv = tmp_path / "m.csv"
    csv.write_text("probe_mm,pressure_mbar,deflection_mm\n6,0,0\n6,50,300\n6,100,500\n")
    from skinsuction.diagnose import diagnose_file
    from skinsuction.measured import MeasuredDataError

    with pytest.raises(MeasuredDataError, match="µm"):
        diagnose_file(csv, spaces=toy_spaces(kinds=()))
    assert load_measured  # same loader


# ------------------------------------------------------------------ workflow (dry run)
def test_workflow_plans_one_fe_job_per_ray(tmp_path):
    import shutil
    import subprocess
    import sys

    for part in ("Snakefile", "workflow", "config", "src", "data"):
        src = ROOT / part
        if src.is_dir():
            shutil.copytree(src, tmp_path / part, ignore=shutil.ignore_patterns("__pycache__"))
        else:
            shutil.copy(src, tmp_path / part)
    counts = {}
    for name in ("config", "ci"):
        # the default study reads the shipped space: its build is the overlay's
        extra = ["config/build_space.yaml"] if name == "config" else []
        res = subprocess.run([sys.executable, "-m", "snakemake", "-n", "--configfile",
                              f"config/{name}.yaml", *extra, "--replace-workflow-config"],
                             cwd=tmp_path, capture_output=True, text=True, timeout=300)
        assert res.returncode == 0, res.stdout + res.stderr
        table = res.stdout.split("Job stats:", 1)[1].splitlines()[3:]
        counts[name] = dict((ln.split()[0], int(ln.split()[1])) for ln in table
                            if len(ln.split()) == 2 and ln.split()[1].isdigit())
        full = yaml.safe_load((tmp_path / "config" / f"{name}.yaml").read_text())
        cfg, sf = full["diagnosis"], full["scale_free_space"]
        spec = RaySpec.from_config(sf)
        causes = registry_from_config(sf["causes"])
        # the jobs are ray_bundles' (the neutral rays once, in the neo-Hookean bundles),
        # and together they run every ray of every model once
        bundles = ray_bundles(spec, causes, sf.get("rays_per_job", 1))
        assert counts[name]["simulate_ray_bundle"] == len(bundles)
        n_rays = sum(len(rays_of(spec, c)) - (len(rays_of(spec)) if c else 0)
                     for c in [None, *causes.values()])
        assert sum(len(b) for b in bundles.values()) == n_rays
        assert len({r for b in bundles.values() for r in b}) == n_rays
        assert counts[name]["assemble_scale_free_space"] == 1 + len(causes)
        assert counts[name]["scale_free_coverage"] == 1
        assert counts[name]["diagnose_measured"] == len(cfg["measured"])
        for rule in ("fig5_measured_identifications", "fig6_measured_vs_simulated",
                     "diagnosis_fe_check"):
            assert counts[name][rule] == 1
        assert "make_example_measurement" not in counts[name]  # the example is shipped
    # 2, 4, 6, 8 mm; 4 causes; about 24 rays a job instead of one job per (model, probe, ratio)
    assert counts["config"]["simulate_ray_bundle"] == 92


# ------------------------------------------------------- identify on the scale-free space
def _toy_csv(path, x1d, r, probes=(6.0,), p_max=100.0, step=2.0):
    p = np.arange(0.0, p_max + 1e-9, step)
    lines = ["probe_mm,pressure_mbar,deflection_mm"]
    for probe in probes:
        m = toy_curve(x1d, r, 0.0, p, probe, BASELINE)
        lines += [f"{probe:g},{a:g},{b:.9f}" for a, b in zip(p, m)]
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize("objective", ["single", "weighted", "ratio"])
def test_identify_on_the_scale_free_space_recovers_the_moduli(objective, tmp_path):
    from skinsuction.space import NeoHookeanSlice
    from skinsuction.identify.measured_fit import identify_measured

    base = toy_spaces()[BASELINE]
    slices = {p: NeoHookeanSlice(base, p) for p in (2.0, 6.0)}
    csv = _toy_csv(tmp_path / "m.csv", 0.047, 0.031, probes=(2.0, 6.0))
    r = identify_measured(csv, spaces=slices, objective=objective, repeats=3, seed=0)
    # the ratio's stop criterion C = 1e-6 is on a dimensionless E: a coarser stop
    tol_um, tol = (0.5, 1e-2) if objective == "ratio" else (0.05, 2e-3)
    assert max(abs(x) for x in r["fit"]["6"]["residual_um"]) < tol_um
    if objective == "single":  # the toy's 6 mm curve depends on X1d / soft(r) only
        return
    assert r["estimate"]["x1d_mpa"] == pytest.approx(0.047, rel=tol)
    assert r["estimate"]["x1h_mpa"] == pytest.approx(0.047 * 0.031, rel=10 * tol)
    assert not any(f["at_bound"] for f in r["at_bound"].values())
    assert r["space"]["kind"] == "scale_free"


def test_identify_flags_a_fit_at_the_edge_of_the_scale_free_space(tmp_path):
    from skinsuction.space import NeoHookeanSlice
    from skinsuction.identify.measured_fit import identify_measured

    base = toy_spaces()[BASELINE]  # X1d window 0.02..0.2 MPa, rays to 5000 mbar/MPa
    slices = {p: NeoHookeanSlice(base, p) for p in (2.0, 6.0)}
    both = {"objective": "weighted", "repeats": 2, "seed": 0}
    # softer than the window: the fit sits on X1d = 0.02 MPa and says so
    r = identify_measured(_toy_csv(tmp_path / "soft.csv", 0.012, 0.031, (2.0, 6.0)),
                          spaces=slices, **both)
    flag = r["at_bound"]["X1d"]
    assert flag["at_bound"] and flag["side"] == "lower" and flag["edge"] == "window"
    assert flag["config_key"] == "scale_free_space.x1d_mpa.min"
    assert any(w.startswith("AT BOUND: X1d") for w in r["warnings"])
    # a 200 mbar protocol raises the lowest X1d to 200 / 5000 = 0.04 MPa: the load's reach
    r = identify_measured(_toy_csv(tmp_path / "long.csv", 0.03, 0.031, (2.0, 6.0), p_max=200,
                                   step=5), spaces=slices, **both)
    flag = r["at_bound"]["X1d"]
    assert flag["at_bound"] and flag["side"] == "lower"
    assert flag["config_key"].startswith("scale_free_space.load.max")
    assert r["space"]["bounds_mpa"]["x1d"][0] == pytest.approx(0.04)
    # a stiff skin inside the window is not flagged
    r = identify_measured(_toy_csv(tmp_path / "stiff.csv", 0.15, 0.031, (2.0, 6.0)),
                          spaces=slices, **both)
    assert not r["at_bound"]["X1d"]["at_bound"]


def test_a_fit_at_a_stopped_ray_is_flagged_as_the_coverage_frontier():
    from skinsuction.identify import bound_flags, single_objective

    from skinsuction.space import NeoHookeanSlice

    s = toy_spaces()[BASELINE]
    rays = {q: a.copy() for q, a in s.deflection_mm.items()}
    rays[6.0][:, :, 11:] = np.nan  # every 6 mm ray stopped at 50 mbar: p/X1d <= 2500
    stopped = RaySpace(None, s.spec, s.coordinates, rays, {})
    p = np.arange(2.0, 101.0, 2.0)
    # the truth X1d = 0.03 needs p/X1d up to 3333: the fit can only reach X1d = 0.04
    m = toy_curve(0.03, 0.031, 0.0, p, 6.0, BASELINE)
    obj = single_objective(NeoHookeanSlice(stopped, 6.0), (p, m))
    theta = np.array([math.log10(0.0401), math.log10(0.031)])
    flags = bound_flags(obj, theta, ["X1d", "X1h"], ["log", "log"])
    assert flags[0]["at_bound"] and flags[0]["edge"] == "coverage"
    assert flags[0]["side"] == "lower"


@pytest.mark.parametrize("noise_um", [None, 2.0])
def test_a_short_curve_is_a_located_input_error(noise_um, tmp_path):
    from skinsuction.diagnose import Settings, diagnose
    from skinsuction.identify.measured_fit import InputError
    from skinsuction.measured import load_measured

    path = tmp_path / "short.csv"
    path.write_text("probe_mm,pressure_mbar,deflection_mm\n6,0,0\n6,50,0.3\n6,100,0.5\n")
    with pytest.raises(InputError) as err:
        diagnose(load_measured(path), toy_spaces(), Settings(noise_um=noise_um))
    assert "short.csv" in str(err.value) and "2 points above 0 mbar" in str(err.value)


# ------------------------------------------------------------ the confusion draws
def test_confusion_draws_in_worker_processes_equal_one_process(monkeypatch):
    """The detectability rule runs its draws in a pool: same rows, same order, same
    seeds as one process (each draw depends on its seed only)."""
    import io
    import os

    import pandas as pd

    from skinsuction.evaluation import _confusion

    def fake_draw(truth, seed, spaces, settings=None, domain=None, cache_dir=None,
                  on_demand=None):
        rng = np.random.default_rng(seed)  # a stand-in for the FE runs and the fit
        return {"truth": truth, "seed": seed, "value": float(rng.normal()),
                "named": truth, "pid": os.getpid(), "n_spaces": len(spaces)}

    monkeypatch.setattr(_confusion, "run_draw", fake_draw)
    spaces = {BASELINE: None, "strain_stiffening": None, "pre_tension": None}
    one = _confusion.run_draws(spaces, 3, seed=7, workers=1)
    log = io.StringIO()
    pool = _confusion.run_draws(spaces, 3, seed=7, workers=2, progress=log)
    cols = ["truth", "seed", "value", "named", "n_spaces"]
    assert one[cols].equals(pool[cols])
    assert one["seed"].tolist() == [7, 8, 9, 100007, 100008, 100009, 200007, 200008, 200009]
    assert one["truth"].tolist() == ["none"] * 3 + ["strain_stiffening"] * 3 + ["pre_tension"] * 3
    assert set(one["pid"]) == {os.getpid()}
    assert os.getpid() not in set(pool["pid"])  # the pool's workers drew them
    assert "detectability: 9/9 draws" in log.getvalue()
    # the workflow's shards: every draw once, and sorted by seed the rows of one run
    shards = [_confusion.run_draws(spaces, 3, seed=7, shard=(j, 4)) for j in range(4)]
    assert [len(s) for s in shards] == [3, 2, 2, 2]
    assert set(shards[0]["truth"]) == {"none", "strain_stiffening", "pre_tension"}  # mixed
    merged = pd.concat(shards, ignore_index=True).sort_values("seed", ignore_index=True)
    assert merged[cols].equals(one[cols])
    with pytest.raises(ValueError, match="shard 4 of 4"):
        _confusion.run_draws(spaces, 3, seed=7, shard=(4, 4))


def test_confusion_draw_with_given_layers_extends_the_dermis_only_draw(monkeypatch):
    """A domain that also gives the hypodermis draws it last: the dermis-only draw of the
    same seed is unchanged, t_h is in its range and given within its sd, and neither
    given thickness is drawn as a cause."""
    from types import SimpleNamespace

    from skinsuction.evaluation import _confusion

    cause = SimpleNamespace(name="pre_tension", value=lambda c, x1d: c)
    dermis = {"given_dermis_thickness": {"range": (0.5, 2.5), "sd": 0.1}}
    both = {**dermis, "given_hypodermis_thickness": {"range": (0.5, 10.0), "sd": 0.2}}
    for seed in range(201000, 201040):
        a = _confusion.draw_wide(seed, cause, dermis)
        b = _confusion.draw_wide(seed, cause, both)
        assert {k: v for k, v in b.items() if k not in ("t_h", "t_h_given")} == \
            {k: v for k, v in a.items() if k not in ("t_h", "t_h_given")}
        assert (a["t_h"], a["t_h_given"]) == (1.0, None)
        assert 0.5 <= b["t_h"] <= 10.0 and abs(b["t_h_given"] - b["t_h"]) < 5 * 0.2 + 0.005
    assert _confusion.given_keywords(both) == ("t_d", "t_h")
    assert _confusion.given_keywords() == ()

    drawn = []
    monkeypatch.setattr(_confusion, "run_draw",
                        lambda truth, seed, *a, **k: drawn.append(truth) or {"truth": truth})
    keyword = {"dermis_thickness": "t_d", "hypodermis_thickness": "t_h",
               "pre_tension": "prestretch"}
    spaces = {BASELINE: None, **{n: SimpleNamespace(cause=SimpleNamespace(keyword=k))
                                 for n, k in keyword.items()}}
    _confusion.run_draws(spaces, 1, seed=0, domain=both)
    assert drawn == ["none", "pre_tension"]
    drawn.clear()
    _confusion.run_draws(spaces, 1, seed=0, domain=dermis)
    assert drawn == ["none", "hypodermis_thickness", "pre_tension"]


def test_confusion_rates_over_distinguishable_draws():
    """The rates separate the misses a diagnosis could avoid from those another cause
    mimics: six detectable thickness draws, two of them mimicked by pre-tension."""
    import pandas as pd

    from skinsuction.evaluation import summarise

    T, P = "dermis_thickness", "pre_tension"
    rows = pd.DataFrame({
        "truth": [T] * 7,
        "named": [T, T, T, P, P, "none", "none"],
        "verdict": ["cause_found"] * 5 + ["unexplained_misfit", "neo_hookean_fits"],
        "detectable": [True] * 6 + [False],
        "distinguishable": [True, True, True, False, True, False, True],
        "ambiguous_with": ["", "", P, T, "", "", ""],
        "x1d": 0.01, "ext_x1d": 0.01, "value": 1.0, "ext_value": 1.0, "base_x1d": 0.01,
    })
    r = summarise(rows, [T, P])["rates"].set_index("truth").loc[T]
    assert r["detectable"] == 6 and r["named_right"] == pytest.approx(3 / 6)
    assert r["distinguishable"] == 4  # of the detectable: rows 0, 1, 2 and 4
    assert r["named_right_distinguishable"] == pytest.approx(3 / 4)
    assert r["right_or_tied"] == pytest.approx(4 / 6)  # row 3 has the truth in the tie
    assert np.isnan(r["ceiling_named_right"])  # no rival gaps in these rows
    rows["rival_gap"] = [50.0, 50.0, 4.0, 0.0, 9.0, 1.0, 0.0]
    r = summarise(rows, [T, P])["rates"].set_index("truth").loc[T]
    from scipy.stats import norm

    phi = norm.cdf(np.sqrt([50.0, 50.0, 4.0, 0.0, 9.0, 1.0]) / 2)
    assert r["ceiling_named_right"] == pytest.approx(phi.mean())


@pytest.mark.parametrize("gap", [0.5, 2.0, 4.0, 9.0])
def test_attribution_ceiling_is_the_chance_the_noisy_chi2_prefers_the_truth(gap):
    # Two one-parameter linear models whose directions differ by a small angle (causes
    # that mimic each other), the truth in the first: on noise-free data the second
    # misses by chi^2 = gap.  With unit Gaussian noise, how often is the truth's chi^2
    # the lower?  Monte Carlo against the closed form.
    from skinsuction.evaluation import attribution_ceiling

    rng = np.random.default_rng(7)
    c = 0.995  # cosine between the two models' directions
    u, v = np.array([1.0, 0.0]), np.array([c, math.sqrt(1 - c * c)])
    truth = math.sqrt(gap / (1 - c * c)) * u
    e = rng.normal(size=(400_000, 2))
    d = truth + e
    chi2_true = (d ** 2).sum(1) - (d @ u) ** 2
    chi2_rival = (d ** 2).sum(1) - (d @ v) ** 2
    mc = float(np.mean(chi2_rival > chi2_true))
    assert attribution_ceiling([gap])[0] == pytest.approx(mc, abs=0.01)
    # the roles swapped: the curves are the rival's, the labelled cause misses by gap
    assert attribution_ceiling([-gap])[0] == pytest.approx(1 - mc, abs=0.01)


# ------------------------------------------- causes' rays on demand in an X1h/X1d window
class _WindowSolver:
    """Serves the toy spaces' rays as a solver on demand would, and records the asks."""

    def __init__(self, spaces):
        self.spaces, self.asked, self.reach = spaces, [], {}

    def rays(self, probe, layers, cause=None, ratio_nodes=None, reads_up_to_mm=None):
        s = self.spaces[BASELINE if cause is None else cause.name]
        nodes = s.spec.ratio_nodes if ratio_nodes is None else tuple(ratio_nodes)
        keep = [s.spec.ratio_nodes.index(r) for r in nodes]
        self.asked.append((None if cause is None else cause.name, nodes))
        self.reach[probe] = reads_up_to_mm
        a = s.rays(probe)[keep]
        return a, {"rays": a.shape[0] * a.shape[1], "stopped_early": 0, "cache": "-"}


@pytest.mark.parametrize("decades", [0.6, 0.15])
def test_causes_solved_in_a_window_around_the_baseline_fit_as_with_every_node(decades):
    from skinsuction.space import Geometry

    spaces = toy_spaces(ratio_nodes=np.geomspace(0.001, 1.0, 13))
    data = _toy_data(0.03, 0.02, 1.1, "pre_tension", 0.5, seed=3)
    given = Geometry(1.2, 1.0, given=("t_d",))  # layers given: causes solved on demand
    reports = {}
    for window in (None, decades):
        solver = _WindowSolver(spaces)
        reports[window] = diagnose(data, spaces, Settings(cause_window_decades=window),
                                   geometry=given, on_demand=solver)
        asked = [len(n) for c, n in solver.asked if c is not None]
        # the solver hears how high a fit reads: twice the largest measured deflection
        for c in data.curves:
            assert solver.reach[c.probe_mm] == pytest.approx(2 * np.max(c.deflection_mm))
        if window is None:
            assert set(asked) == {13}
        else:
            assert max(asked) < 13  # never the whole axis here
            cut = reports[window]
    full = reports[None]
    assert cut["cause"] == full["cause"] == "pre_tension"
    for a, b in zip(full["candidates"], cut["candidates"]):
        assert a["cause"] == b["cause"]
        for k in ("X1d", "X1h", a["extra_parameter"]["symbol"]):
            assert b["parameters"][k] == pytest.approx(a["parameters"][k], rel=2e-3), k
        # an edge of the cut window is never reported as an edge of the space
        assert ({k: f["at_bound"] for k, f in b["at_bound"].items()}
                == {k: f["at_bound"] for k, f in a["at_bound"].items()})
    # pre-tension's fit lies 1.3 decades above the baseline's X1h/X1d (the lowest node)
    assert any(n.startswith("pre_tension: its fit reached") and "widened" in n
               for n in cut["geometry"]["notes"]), cut["geometry"]["notes"]


class _ReadFirst(_WindowSolver):
    """A solver whose causes' rays, read first, are ``error`` off away from the neutral
    node (an interpolation error that grows with the load), as a geometry space's
    can be over its tolerance; :meth:`deferring` gives that view, the solver itself
    the exact rays."""

    tolerance = 0.01

    def __init__(self, spaces, error=0.0):
        super().__init__(spaces)
        self.error, self.deferred = error, []

    def deferring(self):
        return _ReadFirst(self.spaces, error=0.02)

    def rays(self, probe, layers, cause=None, ratio_nodes=None, reads_up_to_mm=None):
        a, info = super().rays(probe, layers, cause, ratio_nodes, reads_up_to_mm)
        if cause is not None and self.error:
            off = np.asarray(cause.nodes) != cause.neutral
            ramp = np.linspace(0.0, 1.0, a.shape[-1])
            a = a * (1 + self.error * off[None, :, None] * ramp)
            self.deferred.append({"cause": cause.name, "rays": a.shape[0],
                                  "largest_error_estimate": self.error})
        return a, info


def test_a_causes_rays_read_first_are_solved_where_its_fit_could_change_the_verdict():
    from skinsuction.space import Geometry

    spaces = toy_spaces(ratio_nodes=np.geomspace(0.001, 1.0, 13))
    data = _toy_data(0.03, 0.02, 1.1, "pre_tension", 0.5, seed=3)
    given = Geometry(1.2, 1.0, given=("t_d",))
    strict = diagnose(data, spaces, Settings(cause_rays_margin_bic=None), geometry=given,
                      on_demand=_ReadFirst(spaces))
    first = diagnose(data, spaces, Settings(), geometry=given, on_demand=_ReadFirst(spaces))
    assert first["verdict"] == strict["verdict"] == "cause_found"
    assert first["cause"] == strict["cause"] == "pre_tension"
    ref = {c["cause"]: c for c in strict["candidates"]}
    assert all(c["rays_deferred"] is None for c in strict["candidates"])
    by = {c["cause"]: c for c in first["candidates"]}
    # pre-tension, decisive with its rays as read, is fitted again with them solved:
    # the fit without the first look, from the same seeds
    held = by["pre_tension"]["rays_deferred"]
    assert held["solved"] and held["delta_bic_read"] < 2.0
    assert by["pre_tension"]["parameters"] == ref["pre_tension"]["parameters"]
    assert by["pre_tension"]["delta_bic"] == ref["pre_tension"]["delta_bic"]
    assert first["extended"]["intervals"] == strict["extended"]["intervals"]
    # stiffening, which the data do not ask for, is left as read, and the report says so
    far = by["strain_stiffening"]["rays_deferred"]
    assert not far["solved"] and far["delta_bic_read"] >= 2.0
    assert by["strain_stiffening"]["delta_bic"] == far["delta_bic_read"]
    assert any(n.startswith("strain_stiffening: ") and "not solved" in n
               for n in first["geometry"]["notes"]), first["geometry"]["notes"]
    assert by["strain_stiffening"]["delta_bic"] == pytest.approx(
        ref["strain_stiffening"]["delta_bic"], abs=0.5)


@pytest.mark.parametrize("tied, measurement, absent", [
    (["pre_tension", "hypodermis_thickness"], "hypodermis thickness", "the dermis thickness"),
    (["dermis_thickness", "pre_tension"], "dermis thickness", "hypodermis"),
    (["pre_tension", "strain_stiffening"], "independent measurement", "thickness"),
])
def test_tie_advice_names_the_thickness_that_decides(tied, measurement, absent):
    # a tie with the free hypodermis must not send the user to measure the dermis
    from skinsuction.diagnose._summary import _tie_breaker_text
    text = _tie_breaker_text(tied)
    assert measurement in text and absent not in text, text
    if "thickness" in measurement:
        key = tied[0] if tied[0].endswith("thickness") else tied[1]
        assert f"# {key}_mm:" in text and f"--{key.replace('_', '-')}-mm" in text


# ------------------------------------------------- detection: with or without the pattern gate
def _candidate(cause, delta_bic, removes=True, at_bound=False):
    flag = {"X1d": {"at_bound": at_bound, "neutral": False, "value": 0.1}}
    return {"cause": cause, "bic": 100.0 + delta_bic, "decisive": delta_bic <= -10,
            "removes_misfit": removes, "at_bound": flag}


@pytest.mark.parametrize("base_misfit, gate, candidates, cause, verdict, tied", [
    # the pattern test fires: either rule names the decisive candidate
    (True, True, [("pre_tension", -30), ("strain_stiffening", -12)], "pre_tension",
     "cause_found", []),
    (True, False, [("pre_tension", -30), ("strain_stiffening", -12)], "pre_tension",
     "cause_found", []),
    # near the noise: only the ungated rule lets the candidate's BIC detect
    (False, True, [("pre_tension", -20), ("strain_stiffening", -16)], "none",
     "neo_hookean_fits", []),
    (False, False, [("pre_tension", -20), ("strain_stiffening", -16)], "pre_tension",
     "cause_found", ["strain_stiffening"]),
    # no decisive candidate: none either way; a misfit left is said
    (False, False, [("pre_tension", -9)], "none", "neo_hookean_fits", []),
    (True, False, [("pre_tension", -9)], "none", "unexplained_misfit", []),
    # a decisive candidate that leaves a misfit detects nothing on its own
    (False, False, [("pre_tension", -40, False)], "none", "neo_hookean_fits", []),
])
def test_decide_with_and_without_the_pattern_gate(base_misfit, gate, candidates, cause,
                                                  verdict, tied):
    from skinsuction.diagnose import decide

    base_bounds = {"X1d": {"at_bound": False, "neutral": False, "value": 0.1}}
    cands = [_candidate(*c) for c in candidates]
    best, named, v, ambiguous, beyond, standing = decide(
        base_misfit, 100.0, base_bounds, cands, Settings(pattern_gate=gate))
    assert (named, v, ambiguous, beyond) == (cause, verdict, tied, [])
    assert (best is None) == (cause == "none")


def test_decide_flags_the_edge_of_the_model_it_stands_on_under_either_rule():
    from skinsuction.diagnose import decide

    base_bounds = {"X1d": {"at_bound": False, "neutral": False, "value": 0.1}}
    for gate in (True, False):
        *_, verdict, _, beyond, standing = decide(
            False, 100.0, base_bounds, [_candidate("pre_tension", -20, at_bound=True)],
            Settings(pattern_gate=gate))
        assert verdict == "beyond_space" and standing == "pre_tension" and beyond


def test_ungated_rule_detects_as_the_likelihood_ratio_predicts_without_false_alarms():
    # A one-parameter effect near the noise: its fitted extra parameter lowers chi^2 by
    # a noncentral chi^2_1 with noncentrality lam, lam the drop on the noise-free curves
    # (mean lam + 1), so the rule's delta chi^2 >= 10 + ln n (k = 1) is reached with
    # probability ncx2.sf(10 + ln n, 1, lam).  On neo-Hookean curves the same rule must
    # name nothing (the chi^2_1 tail beyond 14.6 is ~1e-4 per candidate).
    from scipy import stats

    from skinsuction.diagnose._fit import nested_start, with_space_error

    spaces = toy_spaces()
    noise = 2.0
    fast = Settings(noise_um=noise, repeats=1, holdout=False, pattern_gate=False,
                    window_focusing={"n_samples": 400, "n_best": 10, "tolerance": 1e-6,
                                     "max_iter": 100})
    c, seeds = 1.0075, range(300, 340)
    clean = _toy_data(0.03, 0.02, c, "pre_tension", 0.0, 0)
    fd = {cv.probe_mm: FitData(cv.probe_mm, cv.pressure_mbar[1:], cv.deflection_mm[1:],
                               math.hypot(noise, fast.model_error_um)) for cv in clean.curves}
    # the diagnosis's likelihood: the space's correlated error weighed at the baseline's X1d
    base = fit_model(spaces[BASELINE], fd, seed=0, repeats=1)
    fd = with_space_error(fd, base.parameters["X1d"])
    base = fit_model(spaces[BASELINE], fd, seed=0, repeats=0, starts=[base.theta])
    own = fit_model(spaces["pre_tension"], fd, seed=0, repeats=1,
                    starts=[nested_start(base.theta, spaces["pre_tension"].cause)])
    lam = base.chi2 - own.chi2
    n = sum(d.n for d in fd.values())
    expected = stats.ncx2.sf(-fast.delta_bic + math.log(n), 1, lam)
    assert 0.3 < expected < 0.97  # near the noise: the regime the gate matters in
    drops, named, alarms = [], 0, 0
    for seed in seeds:
        r = diagnose(_toy_data(0.03, 0.02, c, "pre_tension", noise, seed), spaces, fast)
        drops.append(-next(x for x in r["candidates"]
                           if x["cause"] == "pre_tension")["delta_chi2"])
        named += r["cause"] == "pre_tension"
        if seed < 320:
            alarms += diagnose(_toy_data(0.03, 0.02, None, "none", noise, seed), spaces,
                               fast)["cause"] != "none"
    k = len(seeds)
    assert abs(np.mean(drops) - (lam + 1)) < 3 * math.sqrt(2 * (1 + 2 * lam) / k)
    assert abs(named / k - expected) < 3 * math.sqrt(expected * (1 - expected) / k) + 0.05
    assert alarms == 0
