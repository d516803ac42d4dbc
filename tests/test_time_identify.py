"""Identification of time curves (issue 25, part 4): the fit core against FE time solves.

The virtual experiments come from the FE time solve (``simulate_history``: internal
variables, implicit steps), independent of the fast path that the fit uses.  They run
on the default mesh, the mesh of the shipped space: on the coarse mesh the elastic
curve itself differs from the space's by more than the noise, and the test would
measure the mesh, not the method.
"""

import dataclasses
import json

import numpy as np
import pytest

from skinsuction.cli import main
from skinsuction.errors import InputError
from skinsuction.evaluation import mode1_suction, mode2_suction, virtual_curve, write_time_csv
from skinsuction.identify._time_fit import (
    TimeCurveModel,
    _grid_step,
    fit_data_of,
    fit_time_model,
    search_samples,
)
from skinsuction.identify._time_intervals import (
    _segments,
    decorrelate_low_rank,
    rounding_terms,
    sandwich_covariance,
    systematic_basis,
    whitened_systematic,
)
from skinsuction.identify._time_model import ElasticRays, effective_pressures, retardation
from skinsuction.identify import TimeIdentification
from skinsuction.identify.measured_fit import write_identification
from skinsuction.identify.time_curves import identify_time_data
from skinsuction.measured import load_time_curves
from skinsuction.space import RayInterpolant, load_space
from skinsuction.viscoelastic import Prony, effective_pressure

X1D, RATIO, G, TAU = 0.1, 0.05, 0.4, 0.3
FAST_WF = {"n_samples": 600, "max_iter": 40}


@pytest.fixture(scope="module")
def space():
    return load_space()


def _virtual_file(tmp_path, suction, name):
    curves = []
    for k, probe in enumerate((6.0, 2.0)):
        t, p, d, _, _ = virtual_curve(X1D, X1D * RATIO, Prony([G], [TAU]), suction,
                                      probe_mm=probe, seed=10 + k)
        curves.append((probe, t, p, d))
    return load_time_curves(write_time_csv(tmp_path / name, curves, ["synthetic: FE"]))


def _covers(result, truth):
    iv = result.intervals
    return {k: bool(iv[k]["lower"] <= v <= iv[k]["upper"]) for k, v in truth.items()}


TRUTH = {"X1d": X1D, "X1h": X1D * RATIO, "g_1": G, "tau_1": TAU}


def test_creep_function_matches_prony_and_the_scalar_update():
    rng = np.random.default_rng(3)
    t = np.cumsum(rng.uniform(1e-3, 0.05, 200))
    p = np.clip(np.cumsum(rng.normal(0, 20, 200)), 0, None)
    for g, tau in (([0.3], [0.05]), ([0.5, 2.0], [0.01, 0.8])):
        spec = np.log10(np.ravel(np.column_stack([g, tau])))[None, :]
        c, lam = retardation(spec)
        c_ref, lam_ref = Prony(g, tau).retardation()
        assert np.allclose(c[0], c_ref, rtol=1e-10) and np.allclose(lam[0], lam_ref, rtol=1e-10)
        ref = effective_pressure(Prony(g, tau), t, p)
        assert np.max(np.abs(effective_pressures(spec, t, p)[0] - ref)) < 1e-9 * p.max()


def test_elastic_rays_read_at_any_pressure_equal_the_space(space):
    rays = space.probe(6).space
    theta = np.array([[np.log10(0.08), np.log10(0.03)], [np.log10(0.2), np.log10(0.5)]])
    pressures = np.array([37.0, 150.0, 399.0])
    direct = ElasticRays(rays, 6.0, 400.0)(theta, np.tile(pressures, (2, 1)))
    assert np.allclose(direct, RayInterpolant(rays, 6.0, pressures)(theta), rtol=1e-12)


def test_correlated_model_error_covariance():
    """The systematic terms carry the fit's model-error variance (on average over each
    segment of a phase), their Woodbury decorrelation gives the chi^2 of a dense solve,
    and the sandwich covariance is the dense formula (the plain one without them)."""
    curves = load_time_curves("data/example_mode1.csv").curves
    fd = fit_data_of(curves[0])
    B, D = systematic_basis(fd)
    assert B.shape == (fd.n, 3 * 3 + 1)  # on, release, off x degrees 0-2; the space's
    var, sd2, ph = (B ** 2).sum(axis=1) + D, fd.sd_mm[fd.used] ** 2, fd.phase[fd.used]
    for name in ("on", "release", "off"):
        for a, b in _segments(ph, name):
            assert var[a:b].mean() == pytest.approx(sd2[a:b].mean(), rel=1e-9)
    # the same coefficients in every cycle: a phase column repeats over the on segments
    on = _segments(ph, "on")
    assert np.allclose(B[on[0][0]:on[0][1], :-1], B[on[1][0]:on[1][1], :-1])
    # two curves (the first two cycles as such), small enough for a dense solve
    t = fd.time_s
    first = [dataclasses.replace(fd, used=fd.used & (t < 6.0)),
             dataclasses.replace(fd, label="b", used=fd.used & (t >= 6.0) & (t < 11.0))]
    Bw, Dw = whitened_systematic(first)
    n = sum(d.n for d in first)
    assert Bw.shape == (n, 2 * 10) and Dw.shape == (n,) and np.all(Dw <= 1.0 + 1e-12)
    dense = np.diag(Dw) + Bw @ Bw.T
    rng = np.random.default_rng(4)
    z = rng.normal(size=(3, n))
    chi2 = np.sum(decorrelate_low_rank(z, Bw, Dw) ** 2, axis=1)
    assert np.allclose(chi2, np.einsum("kn,kn->k", z, np.linalg.solve(dense, z.T).T),
                       rtol=1e-9)
    J = rng.normal(size=(n, 4))
    H = np.linalg.inv(J.T @ J)
    assert np.allclose(sandwich_covariance(J, Bw, Dw), H @ J.T @ dense @ J @ H, rtol=1e-9)
    assert np.allclose(sandwich_covariance(J, 0 * Bw, np.ones(n)), H, rtol=1e-9)


def _mean_rounding_error(x, q, s):
    """E[round((x + e) / q) q] - x for e ~ N(0, s^2), summed over the grid's bins."""
    from scipy.stats import norm

    n = np.arange(np.floor(x.min() / q) - 12, np.ceil(x.max() / q) + 13)[:, None]
    mass = norm.cdf(((n + 0.5) * q - x) / s) - norm.cdf(((n - 0.5) * q - x) / s)
    return (n * q * mass).sum(axis=0) - x


@pytest.mark.parametrize("beyond", [0.25, 0.4])
def test_rounding_terms_are_the_covariance_of_the_mean_rounding_error(beyond):
    """Over a uniformly random offset of the level against the 0.01 mm grid, the mean
    rounding error (exact, from the normal CDF bin by bin) has the covariance the
    rounding columns give (their Fourier series, 3 harmonics), and its variance is
    taken off the independent noise."""
    q, s = 0.01, beyond * 0.01
    fd = fit_data_of(load_time_curves("data/example_mode1.csv").curves[0])
    fd = dataclasses.replace(fd, resolution_mm=q, noise_sd_mm=float(np.hypot(s, q / np.sqrt(12))))
    x = np.array([0.1234, 0.1271, 0.1302, 0.5555, 0.75])
    cols, var = rounding_terms(fd, np.resize(x, fd.time_s.size))
    cols = cols[:x.size]
    offsets = np.arange(400) / 400 * q  # the integrand is periodic: the rectangle rule is exact
    b = np.array([_mean_rounding_error(x + o, q, s) for o in offsets])
    assert np.allclose(cols @ cols.T, b.T @ b / offsets.size, atol=1e-6 * q ** 2)
    assert var == pytest.approx(np.mean(b ** 2), rel=1e-5)
    # the variance moves from the independent part to the correlated one
    B0, D0 = systematic_basis(fd)
    B1, D1 = systematic_basis(fd, fitted_mm=np.resize(x, fd.time_s.size))
    assert B1.shape[1] == B0.shape[1] + 6
    assert np.allclose(D0 - D1, var)


def test_grid_step_found_only_on_a_grid():
    rng = np.random.default_rng(5)
    on_grid = np.round(rng.uniform(0, 0.08, 300) / 0.01) * 0.01
    assert _grid_step(on_grid) == pytest.approx(0.01)
    assert _grid_step(on_grid + rng.normal(0, 1e-3, 300)) == 0.0


def test_mode1_fe_curve_recovered_within_the_intervals(space, tmp_path):
    data = _virtual_file(tmp_path, mode1_suction(400.0, on_s=2.0, off_s=1.5, cycles=1),
                         "mode1.csv")
    assert data.curve(6).protocol == "mode 1"
    r = identify_time_data(data, space, terms=1, repeats=1, seed=0, window_focusing=FAST_WF)
    assert _covers(r, TRUTH) == {k: True for k in TRUTH}, r.intervals
    assert abs(r.X1d / X1D - 1) < 0.05 and abs(r.g[0] / G - 1) < 0.1
    assert r.X1d_instantaneous == pytest.approx(r.X1d * (1 + r.g[0]))
    assert r.r_parameters["mode1"] and r.fit_quality["reduced_chi2"] < 1.5
    # the typed result: its JSON starts with the kind, the mapping view reads it, and
    # the one writer writes it
    assert isinstance(r, TimeIdentification) and r.kind == "time curves"
    assert list(r.to_json())[:5] == ["kind", "skinsuction_version", "created_utc", "model",
                                     "X1d"]
    assert r["X1d"] == r.X1d and r["kind"] == "time curves" and r.input["sha256"] is None
    paths = write_identification(r, tmp_path / "out")
    written = json.loads(paths["json"].read_text(encoding="utf-8"))
    assert list(written) == list(r.keys()) and written["g"] == r.g


def test_mode2_fe_curve_recovered_within_the_intervals(space, tmp_path):
    data = _virtual_file(tmp_path, mode2_suction(400.0, rate_mbar_s=200.0), "mode2.csv")
    assert data.curve(6).protocol == "mode 2"
    r = identify_time_data(data, space, terms=1, repeats=1, seed=0, window_focusing=FAST_WF)
    cover = _covers(r, TRUTH)
    assert cover["X1d"] and cover["g_1"] and cover["tau_1"], r.intervals
    # X1h's Laplace interval is too narrow here (+-0.4 %, the fit 0.1 % off the truth):
    # the under-coverage the benchmark measures (docs/time_identification.md); checked
    # as a recovery only
    assert abs(r.X1h / (X1D * RATIO) - 1) < 0.01
    assert r.r_parameters["mode2"]


def test_the_search_on_a_fifth_of_the_samples_reaches_the_fit_of_them_all(space, tmp_path):
    """The window focusing reads a subset of the samples (every 8th, and a geometric
    ladder after each break of the suction); the model there is the model of the whole
    curve (the suction is linear between breaks), and the polish on every sample ends
    where the search over every sample ends."""
    data = _virtual_file(tmp_path, mode1_suction(400.0, on_s=2.0, off_s=1.5, cycles=2),
                         "mode1.csv")
    fd = [fit_data_of(c) for c in data.curves]
    sub = [search_samples(d) for d in fd]
    for d, s in zip(fd, sub):
        assert s.time_s.size < d.time_s.size / 3
        assert np.isin(d.time_s[d.breaks], s.time_s).all()
        assert np.isin(np.arange(d.time_s.size)[::8], np.searchsorted(d.time_s, s.time_s)).all()
    rays = {d.probe_mm: space.probe(d.probe_mm).space for d in fd}
    theta = np.array([[np.log10(X1D), np.log10(RATIO), np.log10(G), np.log10(TAU)],
                      [np.log10(0.05), -3.0, 0.3, -1.5]])
    whole, part = TimeCurveModel(rays, fd, 1)(theta), TimeCurveModel(rays, sub, 1)(theta)
    for d, s, m_whole, m_part in zip(fd, sub, whole, part):
        idx = np.searchsorted(d.time_s, s.time_s)
        np.testing.assert_allclose(m_part, m_whole[:, idx], rtol=1e-12, atol=1e-15)
    fits = [fit_time_model(rays, fd, terms=1, seed=0, repeats=1, search_stride=k,
                           window_focusing_options=FAST_WF) for k in (1, 8)]
    assert fits[1].wf["settings"]["search_points"] < sum(d.n for d in fd) / 3
    assert fits[1].chi2 == pytest.approx(fits[0].chi2, rel=1e-6)
    np.testing.assert_allclose(fits[1].theta, fits[0].theta, atol=2e-3)


def test_an_elastic_curve_is_not_given_a_spectrum(space, tmp_path):
    """g = 0 in the FE: the fitted g is small or its interval reaches the lower bound."""
    t, p, d, _, _ = virtual_curve(X1D, X1D * RATIO, Prony.elastic(),
                                  mode1_suction(400.0, on_s=1.0, off_s=1.0, cycles=1),
                                  probe_mm=6.0, seed=1)
    data = load_time_curves(write_time_csv(tmp_path / "el.csv", [(6.0, t, p, d)]))
    r = identify_time_data(data, space, terms=1, repeats=1, window_focusing=FAST_WF)
    assert r.intervals["g_1"]["lower"] < 0.02


def test_suction_beyond_the_space_is_a_located_error(space, tmp_path):
    # a space whose reach is 400 mbar (its largest X1d at p/X1d <= load_max)
    small = dataclasses.replace(space.rays, spec=dataclasses.replace(
        space.rays.spec, x1d_range=(0.001, 400.0 / space.rays.spec.load_max)))
    from skinsuction.space import LoadedSpace

    narrow = LoadedSpace(space.spaces, space.info, None, space.bottom, small, None, None)
    p_of, switches, duration = mode1_suction(500.0, on_s=0.5, off_s=0.5, cycles=1)
    t = np.round(np.arange(0, duration + 0.005, 0.01), 4)
    d = 0.6 * (p_of(t) > 0) + np.random.default_rng(0).normal(0, 0.003, t.size)
    path = write_time_csv(tmp_path / "high.csv", [(6.0, t, p_of(t), d)])
    with pytest.raises(InputError, match=r"high\.csv, line \d+, column pressure_mbar: .*500 "
                                         r"mbar is beyond the reach"):
        identify_time_data(load_time_curves(path), narrow)
    with pytest.raises(InputError, match="1 or 2 Prony terms"):
        identify_time_data(load_time_curves(path), space, terms=3)
    with pytest.raises(InputError, match="no time curve of the 2 mm probe"):
        identify_time_data(load_time_curves(path), space, probes=[2.0])


def test_identify_command_on_the_examples(tmp_path, capsys):
    assert main(["identify", "data/example_mode1.csv", "--repeats", "1",
                 "--out", str(tmp_path / "m1")]) == 0
    out = capsys.readouterr().out
    assert "X1d = " in out and "g_1 = " in out and "R parameters" in out
    r = json.loads((tmp_path / "m1" / "identification.json").read_text())
    assert r["kind"] == "time curves" and len(r["g"]) == len(r["tau_s"]) == 1
    assert r["X1d_instantaneous"] == pytest.approx(r["X1d"] * (1 + r["g"][0]))
    assert len(r["r_parameters"]["mode1"]) == 5 and r["provenance"]["versions"]
    assert set(r["fit_quality"]["curves"][0]["phases"]) >= {"on", "release", "off"}
    assert (tmp_path / "m1" / "fit.png").stat().st_size > 0
    assert main(["identify", "data/example_mode2.csv", "--repeats", "1",
                 "--out", str(tmp_path / "m2")]) == 0
    r2 = json.loads((tmp_path / "m2" / "identification.json").read_text())
    assert r2["r_parameters"]["mode2"] and r2["intervals"]["X1d"]["lower"] > 0
    # a ramp without --objective: a usage error, not a traceback
    assert main(["identify", "data/example_measured.csv", "--out", str(tmp_path / "x")]) == 2
    assert "--objective" in capsys.readouterr().err
