"""The viscoelastic model (issue 25, part 3) against what it must reproduce.

Every check is against something independent of the time-stepping code: the
elastic model (g = 0, and the slow and fast limits, where the error must also
shrink in proportion to tau/T or T/tau), the long-time value after a step, the
order of convergence in the time step, finite differences of the residual, the
scaling and time-scale invariances, and for the fast path the closed form of the
standard linear solid and a numerical solution of its Volterra equation.
Coarse meshes (``refinement: 0.5``, 824 DOFs): each test a few seconds.
"""

import numpy as np
import pytest
from scipy.integrate import quad

from skinsuction.model import ParameterError, Skin, SuctionTest, bulk_modulus, simulate
from skinsuction.viscoelastic import (
    Prony,
    ViscoelasticSuctionTest,
    effective_pressure,
    fast_history,
    graded_steps,
    mode1_history,
    mode2_history,
    simulate_history,
)

COARSE = {"refinement": 0.5}
X1D, X1H = 0.08, 4.1e-3
SPECTRUM = Prony([0.5, 0.3], [0.01, 0.5])  # instantaneous moduli 1.8 X1
P = np.arange(0.0, 81.0, 4.0)


@pytest.fixture(scope="module")
def long_time():
    return simulate(Skin.two_layer(X1D, X1H), pressures_mbar=P, mesh=COARSE)


@pytest.fixture(scope="module")
def instantaneous():
    f = SPECTRUM.instantaneous_factor
    return simulate(Skin.two_layer(X1D * f, X1H * f), pressures_mbar=P, mesh=COARSE)


def rel_error(a, b):
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b))) / np.max(np.abs(b)))


# ------------------------------------------------------------------- Prony
def test_prony_refuses_bad_spectra():
    with pytest.raises(ParameterError):
        Prony([0.5], [0.1, 1.0])
    with pytest.raises(ParameterError):
        Prony([-0.1], [0.1])
    with pytest.raises(ParameterError):
        Prony([0.1], [0.0])


def test_creep_function_of_the_standard_linear_solid():
    # one term: psi(t) = 1 - g/(1+g) exp(-t / (tau (1+g))), in closed form
    g, tau = 1.5, 0.2
    t = np.linspace(0, 3, 31)
    psi = 1 - g / (1 + g) * np.exp(-t / (tau * (1 + g)))
    np.testing.assert_allclose(Prony([g], [tau]).creep(t), psi, rtol=1e-12)
    # a ramp p = r t: p_eff = r (t - c lam (1 - exp(-t/lam))), exact at every point
    c, lam = g / (1 + g), tau * (1 + g)
    p_eff = effective_pressure(Prony([g], [tau]), t, 10.0 * t)
    np.testing.assert_allclose(p_eff, 10.0 * (t - c * lam * (1 - np.exp(-t / lam))), rtol=1e-12)


def test_creep_function_inverts_the_relaxation_function():
    # psi is the Stieltjes inverse of phi: phi(t) psi(0) + int_0^t phi(t-s) psi'(s) ds = 1,
    # checked by scipy's quadrature for a two-term spectrum
    spectrum = Prony([0.5, 1.2], [0.01, 0.4])
    c, lam = spectrum.retardation()
    assert abs(c.sum() - (1 - 1 / spectrum.instantaneous_factor)) < 1e-12

    def dpsi(s):
        return float(np.sum(c / lam * np.exp(-s / lam)))

    for t in (0.003, 0.05, 0.4, 2.0):
        integral, _ = quad(lambda s: spectrum.relaxation(t - s) * dpsi(s), 0, t, limit=200,
                           points=[min(0.05, t / 2)])
        assert abs(spectrum.relaxation(t) * spectrum.creep(0.0) + integral - 1) < 1e-9


def test_effective_pressure_solves_the_volterra_equation():
    # p(t) = int phi(t-s) dp_eff(s), solved step by step on a fine grid (midpoint
    # rule), for a mode-1-like history: its solution must match the exact p_eff
    spectrum = Prony([0.5, 1.2], [0.01, 0.4])
    t = np.linspace(0, 2.0, 4001)
    p = np.interp(t, [0, 0.02, 1.0, 1.02, 2.0], [0, 100, 100, 0, 0])
    q = np.zeros_like(t)
    mid = 0.5 * (t[1:] + t[:-1])
    for n in range(1, len(t)):
        past = spectrum.relaxation(t[n] - mid[: n - 1]) @ np.diff(q[:n])
        q[n] = q[n - 1] + (p[n] - past) / spectrum.relaxation(t[n] - mid[n - 1])
    exact = effective_pressure(spectrum, t, p)
    assert rel_error(q, exact) < 2e-4


# ---------------------------------------------------------------- the FE model
def test_g_zero_is_the_elastic_model(long_time):
    # a: up and back down at g = 0 follows the elastic curve both ways
    times = np.arange(2 * len(P) - 1) * 0.01
    pressures = np.concatenate([P, P[-2::-1]])
    h = simulate_history(Skin.two_layer(X1D, X1H, spectrum=Prony.elastic()), times, pressures, mesh=COARSE)
    assert h.converged
    up, down = h.deflection_mm[: len(P)], h.deflection_mm[len(P) - 1:][::-1]
    assert rel_error(up, long_time.deflection_mm) < 1e-6
    assert rel_error(down, long_time.deflection_mm) < 1e-6


def test_slow_load_gives_the_long_time_response(long_time):
    # b: a ramp over T >> tau; the error is the viscous over-stress, O(tau_max / T)
    errors = []
    for T in (1e3, 1e4):
        h = simulate_history(Skin.two_layer(X1D, X1H, spectrum=SPECTRUM), P / P[-1] * T, P, mesh=COARSE)
        errors.append(rel_error(h.deflection_mm, long_time.deflection_mm))
    assert errors[1] < 2e-5
    assert 5 < errors[0] / errors[1] < 20  # first order in tau / T: the limit, not luck


def test_fast_load_gives_the_instantaneous_response(instantaneous, long_time):
    # c: a ramp over T << tau gives the elastic model at X1 (1 + sum g); error O(T / tau_min)
    errors = []
    for T in (1e-4, 1e-5):
        h = simulate_history(Skin.two_layer(X1D, X1H, spectrum=SPECTRUM), P / P[-1] * T, P, mesh=COARSE)
        errors.append(rel_error(h.deflection_mm, instantaneous.deflection_mm))
    assert errors[1] < 2e-4
    assert 5 < errors[0] / errors[1] < 20
    # and it is not the long-time one
    assert rel_error(instantaneous.deflection_mm, long_time.deflection_mm) > 0.3


def test_fast_load_with_isochoric_branches_keeps_the_bulk_modulus():
    # isochoric branches: instantaneously X1 (1 + sum g) at the long-time bulk
    # modulus, i.e. the elastic model at the Poisson ratio of that pair
    f = SPECTRUM.instantaneous_factor
    ratio = 3 * bulk_modulus(1.0) / (2 * 2.0 * f)  # 3K / (2 mu)
    nu = (ratio - 1) / (2 * ratio + 1)
    reference = SuctionTest(Skin.two_layer(X1D * f, X1H * f), mesh=COARSE, poisson=nu).run(P)
    h = simulate_history(Skin.two_layer(X1D, X1H, spectrum=SPECTRUM), P / P[-1] * 1e-5, P, mesh=COARSE, branches="isochoric")
    assert rel_error(h.deflection_mm, reference.deflection_mm) < 2e-4


def test_creep_after_a_step_tends_to_the_long_time_value(instantaneous, long_time):
    # d: a 10 µs rise to 80 mbar held 20 times the longest retardation time
    lam = SPECTRUM.retardation()[1].max()
    hold = 20 * lam
    t = np.concatenate([[0.0], 1e-5 + np.concatenate([[0.0], graded_steps(hold, 1e-4, 1.3, 0.2)])])
    p = np.where(t > 0, P[-1], 0.0)
    p[1] = P[-1]
    h = simulate_history(Skin.two_layer(X1D, X1H, spectrum=SPECTRUM), t, p, mesh=COARSE)
    m = h.deflection_mm
    assert h.converged
    assert np.all(np.diff(m[1:]) > -1e-12)  # creep only grows
    assert abs(m[1] / instantaneous.deflection_mm[-1] - 1) < 2e-3  # starts instantaneous
    assert abs(m[-1] / long_time.deflection_mm[-1] - 1) < 1e-5  # ends long-time


def test_second_order_in_the_time_step():
    # e: ramp to 80 mbar over 0.1 s, held to 0.3 s; uniform steps 0.1/N against N = 128
    spectrum = Prony([0.5, 1.0], [0.03, 0.1])

    def run(n):
        t = np.arange(3 * n + 1) * (0.1 / n)
        h = simulate_history(Skin.two_layer(X1D, X1H, spectrum=spectrum), t, np.minimum(t / 0.1, 1) * 80, mesh=COARSE, tol=1e-10)
        return h.deflection_mm

    reference = run(128)
    errors = [np.max(np.abs(run(n) - reference[:: 128 // n])) for n in (4, 8, 16)]
    orders = np.log2(np.array(errors[:-1]) / errors[1:])
    assert np.all((orders > 1.8) & (orders < 2.3)), orders


def test_tangent_is_the_derivative_of_the_residual():
    # with a history H != 0 (mid-creep) and the suction on: central differences
    model = ViscoelasticSuctionTest(Skin.two_layer(X1D, X1H, spectrum={"dermis": SPECTRUM,
                                               "hypodermis": Prony([2.0], [0.05])}), mesh=COARSE)
    h = model.run([0, 0.005, 0.02], [0, 60, 60])
    assert h.converged
    asm, m = model.assembly, model.model
    asm.begin_step(0.01)
    m._set_pressure(60.0)
    u = m.field[0].values.reshape(-1).copy()
    K = asm.matrix(asm.tangent(u, m._pressure)).toarray()
    rng = np.random.default_rng(0)
    for dof in rng.choice(m.dof1, 6, replace=False):
        e = np.zeros_like(u)
        e[dof] = 1e-7
        fd = (asm.residual(u + e, m._pressure) - asm.residual(u - e, m._pressure)) / 2e-7
        column = K[asm.position[m.dof1], asm.position[dof]]
        assert np.max(np.abs(column - fd[m.dof1])) < 1e-5 * np.max(np.abs(column))


def test_scaling_and_time_scale_invariance():
    # M(s X1, s p) = M(X1, p) and M(t; tau) = M(k t; k tau), per-layer spectra
    spectra = {"dermis": Prony([0.5], [0.02]), "hypodermis": Prony([1.0, 0.2], [0.1, 1.0])}
    hist = mode1_history(60, on_s=0.3, off_s=0.2, cycles=1, max_step_s=0.05)
    base = simulate_history(Skin.two_layer(X1D, X1H, spectrum=spectra), hist.times_s, hist.pressure_mbar, mesh=COARSE, tol=1e-10)
    scaled = simulate_history(Skin.two_layer(2 * X1D, 2 * X1H, spectrum=spectra), hist.times_s, 2 * hist.pressure_mbar, mesh=COARSE, tol=1e-10)
    slow = {k: Prony(v.g, 3 * np.array(v.tau_s)) for k, v in spectra.items()}
    stretched = simulate_history(Skin.two_layer(X1D, X1H, spectrum=slow), 3 * hist.times_s, hist.pressure_mbar, mesh=COARSE, tol=1e-10)
    assert rel_error(scaled.deflection_mm, base.deflection_mm) < 1e-8
    assert rel_error(stretched.deflection_mm, base.deflection_mm) < 1e-8
    # the spectra matter: the same history with the dermis's alone differs
    dermis_only = simulate_history(Skin.two_layer(X1D, X1H, spectrum={"dermis": spectra["dermis"]}), hist.times_s, hist.pressure_mbar, mesh=COARSE)
    assert rel_error(dermis_only.deflection_mm, base.deflection_mm) > 0.05


# ---------------------------------------------------------------- the fast path
def test_fast_path_is_exact_in_the_linear_limit():
    # at 0.2 mbar the model is linear; the fast path (Laplace-domain creep function)
    # and the FE time solve (internal variables) are independent routes to the same
    spectrum = Prony([0.5, 1.0], [0.03, 0.3])
    hist = mode1_history(0.2, on_s=0.5, off_s=0.5, cycles=1, max_step_s=0.02)
    el = simulate(Skin.two_layer(X1D, X1H), pressures_mbar=np.linspace(0, 0.2, 11), mesh=COARSE)
    fe = simulate_history(Skin.two_layer(X1D, X1H, spectrum=spectrum), hist.times_s, hist.pressure_mbar, mesh=COARSE, tol=1e-10)
    fast = fast_history(el, spectrum, hist.times_s, hist.pressure_mbar)
    assert rel_error(fast, fe.deflection_mm) < 5e-4
    # while the elastic model alone misses by the creep
    elastic = np.interp(hist.pressure_mbar, el.pressure_mbar, el.deflection_mm)
    assert rel_error(elastic, fe.deflection_mm) > 0.2


def test_fast_path_refuses_what_it_cannot_do(long_time):
    hist = mode2_history(100, 50, step_s=0.5)
    with pytest.raises(ParameterError, match="covers"):
        fast_history(long_time, SPECTRUM, hist.times_s, hist.pressure_mbar)  # curve to 80 only
    with pytest.raises(ParameterError, match="one spectrum"):
        fast_history(long_time, {"dermis": SPECTRUM}, [0, 1], [0, 10])


def test_histories():
    h = mode1_history(400, on_s=3, off_s=2, cycles=2)
    assert np.all(np.diff(h.times_s) > 0)
    assert h.times_s[-1] == pytest.approx(10.0)
    on = (h.phase == "rise") | (h.phase == "hold")
    assert np.all(h.pressure_mbar[h.phase == "hold"] == 400)
    assert np.all(h.pressure_mbar[h.phase == "off"] == 0)
    assert on.sum() > 0 and h.phase[0] == "rest"
    m2 = mode2_history(500, 25, step_s=0.25)
    assert m2.times_s[-1] == pytest.approx(40.0) and m2.pressure_mbar.max() == 500


def test_bad_histories_are_refused():
    with pytest.raises(ParameterError):
        simulate_history(Skin.two_layer(X1D, X1H, spectrum=SPECTRUM), [0, 1, 1], [0, 10, 10], mesh=COARSE)
    with pytest.raises(ParameterError):
        simulate_history(Skin.two_layer(X1D, X1H, spectrum=SPECTRUM), [0, 1], [5, 10], mesh=COARSE)


def test_a_time_solve_keeps_its_tangent_from_step_to_step():
    # the last step's tangent starts the next, and one of this step's serves while
    # it contracts: one factorisation a step (2.2 when every step began afresh and
    # refactorised from its 3rd iteration), with the history of a tolerance 10^4
    # times tighter. A soft dermis, the study's mode 1 and time steps
    skin = Skin.two_layer(0.02, 6e-4, spectrum=Prony([0.4, 0.6], [0.05, 2.0]))
    hist = mode1_history(150, on_s=1.0, off_s=0.5, cycles=2, growth=1.5, max_step_s=0.15)
    model = ViscoelasticSuctionTest(skin, 2.0, mesh=COARSE)
    factorised, tangent = [], model.model._tangent
    model.model._tangent = lambda: factorised.append(1) or tangent()
    h = model.run(hist.times_s, hist.pressure_mbar)
    tight = ViscoelasticSuctionTest(skin, 2.0, mesh=COARSE).run(hist.times_s, hist.pressure_mbar,
                                                                tol=1e-10)
    assert h.converged and tight.converged
    assert len(factorised) <= 1.25 * h.steps, (len(factorised), h.steps)
    assert rel_error(h.deflection_mm, tight.deflection_mm) < 1e-6
