"""Identification: interpolation, cost functions and window focusing (paper 2.3-2.4, 3.2-3.3).

The simulated spaces here come from the analytic surrogate of
``skinsuction.identify._surrogate`` on the paper's 11 x 11 x 51 grid; the tests
check facts that do not depend on the FE model.
"""

import numpy as np
import pytest
from scipy.interpolate import BarycentricInterpolator

from skinsuction.identify import PAPER_PRESSURE_MBAR, PAPER_X1D, PAPER_X1H, IdentificationError, analytic_surrogate_space, correlation_error, cost, identify_repeated, ratio_objective, samples_for, single_objective, surrogate_deflection, weighted_objective, window_focusing
from skinsuction.evaluation import differential_evolution_fit, least_squares_from_random_starts
from skinsuction.space import GriddedSpace, LagrangeAxis, SpaceInterpolant, evaluate, interpolate_pressure

TRUTH = np.array([0.0055, 0.00041])  # the paper's test parameters (section 3.2)


@pytest.fixture(scope="module")
def s6():
    return analytic_surrogate_space(6.0)


@pytest.fixture(scope="module")
def s2():
    return analytic_surrogate_space(2.0)


def simulated_curve(space, x=TRUTH, pressure=None):
    """A curve "extracted from the database" (paper 3.2): the interpolated space at x."""
    p = space.pressure_mbar if pressure is None else np.asarray(pressure, float)
    return p, evaluate(space, [x], p)[0]


# ------------------------------------------------------------------ the space
def test_gridded_space_checks_shapes_and_is_read_only():
    with pytest.raises(ValueError, match="shape"):
        GriddedSpace([1, 2], [1, 2, 3], [0, 1], np.zeros((2, 2, 2)), 6)
    with pytest.raises(ValueError, match="increasing"):
        GriddedSpace([2, 1], [1, 2], [0, 1], np.zeros((2, 2, 2)), 6)
    s = GriddedSpace([1, 2], [1, 2], [0, 1], np.zeros((2, 2, 2)), 6)
    with pytest.raises(ValueError):
        s.deflection_mm[0, 0, 0] = 1.0


def test_gridded_space_from_a_stored_space():
    class Stored:  # the interface of skinsuction.space.SimulatedSpace.grid
        def grid(self, probe_mm, bottom="fixed"):
            assert (probe_mm, bottom) == (6.0, "axial")
            return PAPER_X1D, PAPER_X1H, PAPER_PRESSURE_MBAR, np.zeros((11, 11, 51))

    s = GriddedSpace.from_space(Stored(), 6.0, bottom="axial")
    assert s.shape == (11, 11, 51) and s.probe_mm == 6.0
    np.testing.assert_array_equal(s.lower, [0.001, 1e-5])
    np.testing.assert_allclose(s.upper, [0.091, 2.01e-3])


# ------------------------------------------------------------ interpolation
def _random_space(seed=0, x1d=PAPER_X1D, x1h=PAPER_X1H, p=(0.0, 10.0, 20.0)):
    rng = np.random.default_rng(seed)
    m = rng.normal(size=(len(x1d), len(x1h), len(p)))
    return GriddedSpace(x1d, x1h, p, m, 6.0)


def test_interpolation_is_exact_at_grid_nodes():
    s = _random_space()
    nodes = np.array([(a, b) for a in s.x1d for b in s.x1h])
    got = SpaceInterpolant(s)(nodes)
    np.testing.assert_array_equal(got, s.deflection_mm.reshape(-1, 3))


def _tensor_polynomial(x1d, x1h, degree, seed=1):
    """sum_{i,j <= degree} c_ij u^i v^j on unit-scaled axes, c random."""
    c = np.random.default_rng(seed).normal(size=(degree + 1, degree + 1))
    u = (np.asarray(x1d) - 0.046) / 0.045
    v = (np.asarray(x1h) - 0.00101) / 0.001
    return sum(c[i, j] * u**i * v**j for i in range(degree + 1) for j in range(degree + 1))


@pytest.mark.parametrize("x1d", [PAPER_X1D, np.array([0.001, 0.004, 0.01, 0.02, 0.045, 0.06, 0.091])],
                         ids=["paper grid", "non-uniform grid"])
def test_interpolation_reproduces_bicubic_polynomials_off_grid(x1d):
    """Independent check of the order: cubic in each variable is exact, quartic is not."""
    rng = np.random.default_rng(2)
    x = np.column_stack([rng.uniform(x1d[0], x1d[-1], 500), rng.uniform(1e-5, 2.01e-3, 500)])
    for degree, exact in ((3, True), (4, False)):
        values = _tensor_polynomial(x1d[:, None], PAPER_X1H[None, :], degree)
        space = GriddedSpace(x1d, PAPER_X1H, [50.0], values[..., None], 6.0)
        got = SpaceInterpolant(space)(x)[:, 0]
        want = _tensor_polynomial(x[:, 0], x[:, 1], degree)
        err = np.max(np.abs(got - want)) / np.max(np.abs(want))
        assert (err < 1e-11) == exact, (degree, err)


def test_short_axis_uses_a_lower_order_stencil():
    """3 nodes in X1h: quadratic there (and the un-fused code path) is exact."""
    x1h = np.array([1e-5, 1e-3, 2.01e-3])
    values = _tensor_polynomial(PAPER_X1D[:, None], x1h[None, :], 2)
    space = GriddedSpace(PAPER_X1D, x1h, [50.0], values[..., None], 6.0)
    rng = np.random.default_rng(5)
    x = np.column_stack([rng.uniform(0.001, 0.091, 100), rng.uniform(1e-5, 2.01e-3, 100)])
    got = SpaceInterpolant(space)(x)[:, 0]
    np.testing.assert_allclose(got, _tensor_polynomial(x[:, 0], x[:, 1], 2), rtol=1e-10, atol=1e-12)


def test_one_dimensional_weights_match_scipy_lagrange():
    ax = LagrangeAxis(PAPER_X1H)
    x = np.random.default_rng(3).uniform(PAPER_X1H[0], PAPER_X1H[-1], 50)
    start, w = ax.weights(x)
    f = np.sin(PAPER_X1H * 3e3)
    for xi, s, wi in zip(x, start, w):
        stencil = slice(s, s + 4)
        assert PAPER_X1H[s] <= xi <= PAPER_X1H[s + 3]
        lag = BarycentricInterpolator(PAPER_X1H[stencil], f[stencil])(xi)
        assert np.isclose(wi @ f[stencil], lag, rtol=1e-10, atol=1e-12)


def test_pressure_interpolation_is_cubic_and_exact_on_grid_pressures():
    p = PAPER_PRESSURE_MBAR
    m = np.broadcast_to(1e-6 * p**3 - 2e-4 * p**2 + 0.01 * p, (11, 11, 51))
    s = GriddedSpace(PAPER_X1D, PAPER_X1H, p, m, 6.0)
    q = np.array([0.0, 1.3, 37.7, 50.0, 99.9, 100.0])
    got = interpolate_pressure(s, q).deflection_mm[3, 4]
    np.testing.assert_allclose(got, 1e-6 * q**3 - 2e-4 * q**2 + 0.01 * q, rtol=1e-12, atol=1e-15)
    assert interpolate_pressure(s, [50.0]).deflection_mm[3, 4, 0] == m[3, 4, 25]
    with pytest.raises(ValueError, match="outside the simulated range"):
        interpolate_pressure(s, [101.0])


def test_vectorised_evaluation_equals_candidate_by_candidate(s6):
    rng = np.random.default_rng(4)
    x = s6.lower + (s6.upper - s6.lower) * rng.random((300, 2))
    interp = SpaceInterpolant(s6)
    together = interp(x)
    one_by_one = np.vstack([interp(xi[None]) for xi in x])
    np.testing.assert_allclose(together, one_by_one, rtol=0, atol=1e-15)


def test_points_outside_the_space_are_nan(s6):
    got = SpaceInterpolant(s6)([[0.0005, 1e-4], [0.05, 3e-3], [np.nan, 1e-4], [0.05, 1e-3]])
    assert np.isnan(got[:3]).all() and np.isfinite(got[3]).all()


def test_non_converged_nodes_make_their_stencil_infinite_cost(s6):
    """Policy: a candidate whose 4x4 (X1d, X1h) stencil touches a NaN node costs +inf."""
    m = s6.deflection_mm.copy()
    m[9:, 9:, 40:] = np.nan  # stiffest corner fails above 80 mbar
    broken = GriddedSpace(s6.x1d, s6.x1h, s6.pressure_mbar, m, 6.0)
    obj = single_objective(broken, simulated_curve(s6))
    # stencil of cell [x1d_8, x1d_9] is nodes 7..10, which holds node 9: inf
    near = [(s6.x1d[8] + s6.x1d[9]) / 2, (s6.x1h[8] + s6.x1h[9]) / 2]
    # stencil of cell [x1d_6, x1d_7] is nodes 5..8: finite
    far = [(s6.x1d[6] + s6.x1d[7]) / 2, (s6.x1h[8] + s6.x1h[9]) / 2]
    assert obj([near])[0] == np.inf and np.isfinite(obj([far])[0])
    # a curve that stops at 60 mbar does not see the NaN above 80 mbar
    obj60 = single_objective(broken, simulated_curve(s6, pressure=np.arange(0, 61, 5.0)))
    assert np.isfinite(obj60([near])[0])
    # and the window focusing still finds the truth
    r = window_focusing(obj, seed=0)
    np.testing.assert_allclose(r.estimate, TRUTH, rtol=1e-4)


# ---------------------------------------------------------------- objectives
def test_cost_eq4_and_correlation_error_eq7_by_hand():
    d = np.array([[3.0, 4.0], [1.0, 0.0]])
    np.testing.assert_array_equal(cost(d), [12.5, 0.5])
    np.testing.assert_array_equal(correlation_error(d), [2.5, 0.5])  # (1/u) sqrt(sum d^2)


def test_single_objective_cost_and_error_in_micrometres(s6):
    p, m = simulated_curve(s6)
    offset = 0.002  # mm, added at every pressure
    obj = single_objective(s6, (p, m + offset))
    j = obj([TRUTH])[0]
    assert np.isclose(j, 0.5 * p.size * offset**2, rtol=1e-9)
    want_um = 1000 * np.sqrt(p.size * offset**2) / p.size  # eq. 7
    assert np.isclose(obj.error(j), want_um, rtol=1e-9)
    assert obj.error_unit == "µm"


def test_single_objective_rejects_a_curve_of_the_other_probe(s6):
    class Curve:
        probe_mm, pressure_mbar, deflection_mm = 2.0, np.array([0.0, 10.0]), np.array([0, 0.1])

    with pytest.raises(ValueError, match="2 mm probe"):
        single_objective(s6, Curve())


def test_weighted_objective_eq10(s2, s6):
    c2 = simulated_curve(s2)
    c6 = (s6.pressure_mbar, simulated_curve(s6)[1] + 0.01)
    x = np.array([TRUTH, [0.02, 0.001]])
    j2, j6 = single_objective(s2, c2)(x), single_objective(s6, c6)(x)
    for alpha in (0.0, 0.25, 1.0):
        w = weighted_objective(s2, c2, s6, c6, alpha=alpha)
        np.testing.assert_allclose(w(x), alpha * j2 + (1 - alpha) * j6, rtol=1e-12)
        np.testing.assert_allclose(0.5 * np.sum(w.residuals(x) ** 2, axis=1), w(x), rtol=1e-12)
    # at alpha = 0 its E is eq. 7 of the 6 mm curve
    w0 = weighted_objective(s2, c2, s6, c6, alpha=0.0)
    assert np.isclose(w0.error(w0(x)[0]), single_objective(s6, c6).error(j6[0]))
    with pytest.raises(ValueError, match="alpha"):
        weighted_objective(s2, c2, s6, c6, alpha=1.5)


def test_ratio_objective_excludes_p0_and_is_eq11_12(s2, s6):
    c2, c6 = simulated_curve(s2), simulated_curve(s6, x=[0.02, 0.001])
    r = ratio_objective(s2, c2, s6, c6)
    assert r.excluded_pressures_mbar.tolist() == [0.0]
    assert 0.0 not in r.pressure_mbar and r.n_points == 50
    x = np.array([[0.03, 0.0005]])
    keep = slice(1, None)
    theta = evaluate(s6, x)[0, keep] / evaluate(s2, x)[0, keep]
    gamma = c6[1][keep] / c2[1][keep]
    assert np.isclose(r(x)[0], 0.5 * np.sum((gamma - theta) ** 2), rtol=1e-10)
    assert r.error_unit == "1"


def test_ratio_objective_uses_common_pressures_and_skips_zero_deflections(s2, s6):
    p2, m2 = simulated_curve(s2, pressure=[0, 10, 20, 30, 40])
    m2 = m2.copy()
    m2[1] = 0.0  # below the resolution of the device at 10 mbar
    c6 = simulated_curve(s6, pressure=[0, 20, 25, 40, 60])
    r = ratio_objective(s2, (p2, m2), s6, c6)
    assert r.pressure_mbar.tolist() == [20.0, 40.0]
    assert r.excluded_pressures_mbar.tolist() == [0.0]  # 10 mbar is not common anyway
    r2 = ratio_objective(s2, (p2, m2), s6, simulated_curve(s6, pressure=[0, 10, 20]))
    assert r2.excluded_pressures_mbar.tolist() == [0.0, 10.0]


# ----------------------------------------------------------- window focusing
def test_eq8_number_of_samples():
    assert samples_for(0.99, 0.01) == 459  # ln(0.01) / ln(0.99) = 458.2
    assert samples_for(0.95, 0.05) == 59  # ln(0.05) / ln(0.95) = 58.4
    with pytest.raises(ValueError):
        samples_for(1.0, 0.01)


def test_recovers_the_paper_parameters_on_the_6mm_space(s6):
    """Paper 3.2: a curve extracted from the 6 mm space is identified in every run."""
    obj = single_objective(s6, simulated_curve(s6))
    rep = identify_repeated(obj, repeats=20, seed=0)
    assert rep.converged.all()
    np.testing.assert_allclose(rep.estimates, np.tile(TRUTH, (20, 1)), rtol=1e-4)
    assert rep.E.max() < 1e-3  # µm
    assert 3 <= rep.iterations.mean() <= 30


def test_recovers_parameters_from_an_analytic_curve_off_the_grid(s6):
    """The curve comes from the analytic function, not the grid: interpolation error only."""
    x = np.array([0.05, 0.0011])
    p = np.linspace(0, 100, 73)  # not the 2 mbar grid
    obj = single_objective(s6, (p, surrogate_deflection(*x, p, 6.0)))
    r = window_focusing(obj, seed=3)
    assert r.converged
    np.testing.assert_allclose(r.estimate, x, rtol=0.01)


def test_weighted_objective_recovers_the_paper_parameters(s2, s6):
    """Paper 3.3.1: alpha = 0.5 identifies the parameters in every case."""
    obj = weighted_objective(s2, simulated_curve(s2), s6, simulated_curve(s6), alpha=0.5)
    rep = identify_repeated(obj, repeats=10, seed=5)
    assert rep.converged.all()
    np.testing.assert_allclose(rep.estimates, np.tile(TRUTH, (10, 1)), rtol=1e-4)


def test_ratio_objective_recovers_the_paper_parameters(s2, s6):
    """Paper 3.3.2.  On the surrogate some runs collapse onto a wrong window (the
    ratio valley is narrow and oblique), so the median of the runs is checked."""
    obj = ratio_objective(s2, simulated_curve(s2), s6, simulated_curve(s6))
    rep = identify_repeated(obj, repeats=10, seed=5, tolerance=1e-12)
    np.testing.assert_allclose(np.median(rep.estimates, axis=0), TRUTH, rtol=1e-3)
    assert np.isclose(obj([TRUTH])[0], 0.0, atol=1e-20)


def _record(states):
    return lambda state: states.append(state)


def test_eq6_window_update_and_uniform_samples_in_the_window(s6):
    obj = single_objective(s6, simulated_curve(s6))
    states = []
    r = window_focusing(obj, seed=7, n_samples=500, n_best=15, callback=_record(states))
    assert len(states) == r.iterations and len(r.windows) == r.iterations + 1
    np.testing.assert_array_equal(r.windows[0][0], s6.lower)
    np.testing.assert_array_equal(r.windows[0][1], s6.upper)
    for j, st in enumerate(states, start=1):
        lower, upper = r.windows[j - 1]
        assert st.samples.shape == (500, 2)
        assert np.all(st.samples >= lower) and np.all(st.samples <= upper)
        np.testing.assert_array_equal(st.costs, obj(st.samples))
        nb = st.samples[np.argsort(st.costs)[:15]]  # independent sort
        np.testing.assert_array_equal(r.windows[j][0], nb.min(axis=0))
        np.testing.assert_array_equal(r.windows[j][1], nb.max(axis=0))
    assert r.n_evaluations == 500 * r.iterations
    np.testing.assert_array_equal(r.estimate, states[-1].samples[states[-1].best[0]])


def test_stop_criterion_is_the_first_small_change_of_E(s6):
    p, m = simulated_curve(s6)
    obj = single_objective(s6, (p, m + 0.003 * np.sin(p / 15)))  # E > 0 at the optimum
    C = 1e-6
    r = window_focusing(obj, seed=11, tolerance=C)
    changes = np.abs(np.diff(r.E_history))
    assert r.converged and changes[-1] < C and np.all(changes[:-1] >= C)
    assert r.E == r.E_history[-1] and np.isclose(obj.error(r.cost), r.E)
    # same seed, larger C: the same samples, so it stops at an earlier iteration
    coarse = window_focusing(obj, seed=11, tolerance=1e-2)
    assert coarse.iterations < r.iterations
    np.testing.assert_array_equal(coarse.E_history, r.E_history[: coarse.iterations])


def test_max_iter_guard_flags_non_convergence(s6):
    obj = single_objective(s6, simulated_curve(s6))
    r = window_focusing(obj, seed=0, tolerance=0.0, max_iter=5)
    assert not r.converged and r.iterations == 5


def test_seed_reproducibility(s6):
    obj = single_objective(s6, simulated_curve(s6, x=[0.03, 0.0009]))
    first = []
    a = window_focusing(obj, seed=42, callback=_record(first))
    again = []
    b = window_focusing(obj, seed=42, callback=_record(again))
    np.testing.assert_array_equal(a.estimate, b.estimate)
    np.testing.assert_array_equal(a.E_history, b.E_history)
    np.testing.assert_array_equal(first[0].samples, again[0].samples)
    other = []
    window_focusing(obj, seed=43, callback=_record(other))
    assert not np.array_equal(first[0].samples, other[0].samples)
    # repeated identifications: reproducible as a whole, independent between runs
    r1, r2 = identify_repeated(obj, repeats=4, seed=9), identify_repeated(obj, repeats=4, seed=9)
    np.testing.assert_array_equal(r1.estimates, r2.estimates)
    assert len({tuple(e) for e in r1.estimates}) == 4


def test_all_infinite_costs_fail_clearly(s6):
    nan_space = GriddedSpace(s6.x1d, s6.x1h, s6.pressure_mbar, np.full(s6.shape, np.nan), 6.0)
    obj = single_objective(nan_space, simulated_curve(s6))
    with pytest.raises(IdentificationError, match="infinite cost"):
        window_focusing(obj, seed=0)


def test_repeated_identification_summary(s6):
    obj = single_objective(s6, simulated_curve(s6))
    rep = identify_repeated(obj, repeats=5, seed=1)
    s = rep.summary()
    assert s["repeats"] == 5 and s["converged_fraction"] == 1.0
    assert np.isclose(s["x1d_mean"], TRUTH[0], rtol=1e-3)
    assert rep.relative_error(TRUTH).shape == (5, 2)


# ------------------------------------------------------------ the fitting engine
def test_focus_is_window_focusing_with_the_rng_an_argument(s6):
    from skinsuction.identify import focus

    obj = single_objective(s6, simulated_curve(s6))
    a = focus(obj, None, np.random.default_rng(3))
    b = window_focusing(obj, seed=3)
    np.testing.assert_array_equal(a.estimate, b.estimate)
    assert a.E_history.tolist() == b.E_history.tolist()
    with pytest.raises(TypeError, match="seed"):
        focus(obj, None, None)


def test_repeated_fit_median_is_the_ramp_identification_rule(s2, s6):
    # identify_data: 100 runs (here 6), their median, the polish from it; the engine's
    # estimate="median" is the same numbers, bit for bit
    from skinsuction.identify import polish, repeated_fit

    obj = weighted_objective(s2, simulated_curve(s2), s6, simulated_curve(s6))
    rep = identify_repeated(obj, repeats=6, seed=4)
    by_hand = polish(obj, np.median(rep.estimates, axis=0))
    fit = repeated_fit(obj, repeats=6, seed=4, estimate="median", skip_failed=False)
    np.testing.assert_array_equal(fit.runs.estimates, rep.estimates)
    np.testing.assert_array_equal(fit.start, np.median(rep.estimates, axis=0))
    np.testing.assert_array_equal(fit.x, by_hand)
    assert fit.cost == obj(by_hand[None, :])[0] and fit.polished == 1
    with pytest.raises(ValueError, match="starts"):
        repeated_fit(obj, repeats=1, estimate="median", starts=[TRUTH])


def test_repeated_fit_takes_the_best_of_runs_and_starts_and_polishes_it():
    from skinsuction.identify import Chi2Objective, repeated_fit

    x = np.linspace(0.0, 1.0, 30)
    y = 0.3 + 0.7 * x

    class Line(Chi2Objective):
        def blocks(self, t):
            return [(y - t[:, :1] - t[:, 1:] * x) / 0.01]

    obj = Line([-1.0, -1.0], [1.0, 1.0], x.size)
    # no runs: the usable start is the only candidate, polished onto the truth; a start
    # of another size is left out
    fit = repeated_fit(obj, repeats=0, starts=[[0.2, 0.6], [0.1, 0.2, 0.3]])
    assert len(fit.candidates) == 1 and fit.polished == 1
    np.testing.assert_allclose(fit.x, [0.3, 0.7], atol=1e-9)
    assert fit.cost < 1e-12 and fit.summary()["runs"] == 0
    unpolished = repeated_fit(obj, repeats=2, seed=1, starts=[[0.3, 0.7]], polish_best=0)
    np.testing.assert_array_equal(unpolished.x, [0.3, 0.7])  # the start beats the runs
    assert unpolished.polished == 0 and unpolished.summary()["runs"] == 2
    with pytest.raises(IdentificationError, match="nothing fits"):
        repeated_fit(obj, repeats=0, starts=[[0.1]], error_message="nothing fits")


def test_chi2_objective_adds_its_blocks_and_prior():
    from skinsuction.identify import Chi2Objective

    class Two(Chi2Objective):
        def blocks(self, t):
            return [t[:, :1] - 1.0, 2.0 * t[:, :2]]

        def prior_residuals(self, t):
            return t[:, 2:]

    obj = Two(np.zeros(3), np.ones(3), n=3, chunk_values=16)
    t = np.random.default_rng(0).random((50, 3))
    r = obj.residuals(t)
    assert r.shape == (50, 4)
    np.testing.assert_allclose(obj(t), 0.5 * (r ** 2).sum(axis=1), rtol=1e-14)
    assert obj.error(obj(t[:1])[0]) == pytest.approx(np.sqrt((r[0] ** 2).sum() / 3))
    t[3, 0] = np.nan
    assert obj(t)[3] == np.inf


def test_polish_run_reports_a_refused_start():
    from skinsuction.identify import POLISH, polish_run

    class Flat:
        lower, upper = np.zeros(2), np.zeros(2)  # a box of no width: the solver refuses

        def residuals(self, t):
            return np.atleast_2d(t)

        def __call__(self, t):
            return 0.5 * (np.atleast_2d(t) ** 2).sum(axis=1)

    p = polish_run(Flat(), [0.5, 0.5])
    assert not p.ran and p.best.tolist() == [0.0, 0.0] and p.cost == p.start_cost
    with pytest.raises(TypeError, match="unknown polish settings"):
        polish_run(Flat(), [0.0, 0.0], max_iter=3)
    assert POLISH["max_nfev"] == 200 and POLISH["tol"] == 1e-12


# ----------------------------------------------------------------- baselines
@pytest.mark.parametrize("fit", [least_squares_from_random_starts, differential_evolution_fit])
def test_baselines_recover_the_paper_parameters(s6, fit):
    obj = single_objective(s6, simulated_curve(s6))
    r = fit(obj, seed=0)
    assert r.success and r.n_evaluations > 0 and r.seconds > 0
    np.testing.assert_allclose(r.estimate, TRUTH, rtol=1e-3)
    assert np.isclose(r.cost, obj([r.estimate])[0])


def test_compare_spaces_runs_every_objective_with_and_without_polish():
    from skinsuction.identify import analytic_surrogate_space
    from skinsuction.space import evaluate
    from skinsuction.paper import StudySetup, compare_spaces

    s = {p: analytic_surrogate_space(p) for p in (2.0, 6.0)}
    # a curve between grid nodes: the window focusing alone stops short of it
    truth = [0.0055, 0.00041]
    curves = {"fe": {p: (s[p].pressure_mbar, evaluate(s[p], [truth])[0]) for p in s}}
    runs, summary = compare_spaces({"surrogate": StudySetup(s, curves, truth)}, repeats=4, seed=1)
    assert len(runs) == 4 * 4 * 2
    assert set(summary["method"]) == {"window focusing", "window focusing + polish"}
    by = summary.set_index(["objective", "method"])
    for kind in ("single_6mm", "weighted"):
        wf = abs(by.loc[(kind, "window focusing"), "x1d_error_median_pct"])
        pol = abs(by.loc[(kind, "window focusing + polish"), "x1d_error_median_pct"])
        assert pol <= wf + 1e-6 and pol < 0.01


def test_identify_data_returns_an_identification_whose_json_is_the_file(s2, s6, tmp_path):
    # the typed result: named fields; to_json() is identification.json key for key, in
    # order; result["key"] (the mapping view) reads it; the one writer writes it
    import json

    from skinsuction.identify import Identification
    from skinsuction.model import Skin
    from skinsuction.identify.measured_fit import identify_data, write_identification
    from skinsuction.measured import MeasuredCurve, MeasuredData
    from skinsuction.space import LoadedSpace

    rng = np.random.default_rng(3)
    curves = tuple(MeasuredCurve(p, s.pressure_mbar, evaluate(s, [[0.03, 5e-4]])[0]
                                 + rng.normal(0, 1e-3, s.pressure_mbar.size))
                   for p, s in ((2.0, s2), (6.0, s6)))
    r = identify_data(MeasuredData("m.csv", curves), LoadedSpace.given({2.0: s2, 6.0: s6}),
                      objective="weighted", repeats=2, noise_um=1.0)
    assert isinstance(r, Identification)
    doc = r.to_json()
    assert list(doc) == ["skinsuction_version", "created_utc", "input", "space", "settings",
                         "estimate", "at_bound", "best_run", "spread", "E", "iterations",
                         "noise", "intervals", "geometry", "fit", "runs", "warnings", "skin"]
    assert r.x1d_mpa == doc["estimate"]["x1d_mpa"] == pytest.approx(0.03, rel=0.05)
    # the fitted skin: the estimate on the layers assumed
    skin = Skin.from_dict(doc["skin"])
    assert skin.get("dermis.X1") == r.x1d_mpa and skin.get("hypodermis.X1") == r.x1h_mpa
    assert skin.thicknesses == (1.0, 1.0)
    assert r["intervals"] is r.intervals and r.get("nothing", 1) == 1
    assert list(r.keys()) == list(doc) and "fit" in r and "kind" not in r
    assert r.input["sha256"] is None and r.settings["objective"] == "weighted"
    paths = write_identification(r, tmp_path)
    written = json.loads(paths["json"].read_text(encoding="utf-8"))
    assert list(written) == list(doc) and written["estimate"] == doc["estimate"]
    assert paths["png"].stat().st_size > 0 and paths["pdf"].stat().st_size > 0
