"""Reading a ray along its load (skinsuction.space.LoadAxis): exactness, stopped rays,
and its accuracy against direct FE runs where the first scheme (M in q) missed."""

import numpy as np
import pytest

from skinsuction.model import Skin, simulate
from skinsuction.space import LagrangeAxis, LoadAxis, read_ray_spaces
from skinsuction.space import BASELINE, SHIPPED_SPACE_DIR

LOADS = np.array([0.0, 0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 12.0, 16.0, 20.0, 24.0])


def _read(axis, log_m, q):
    return axis.read(log_m, axis.weights(q))


def test_exact_for_log_m_cubic_in_log_q_above_the_first_load_and_m_cubic_in_q_below():
    axis = LoadAxis(LOADS)
    x = np.log(LOADS[1:])
    log_m = (0.2 + 0.9 * x - 0.08 * x ** 2 + 0.01 * x ** 3)[None, :]
    rng = np.random.default_rng(0)
    q = rng.uniform(LOADS[1], LOADS[-1], (1, 200))
    lq = np.log(q)
    np.testing.assert_allclose(_read(axis, log_m, q),
                               np.exp(0.2 + 0.9 * lq - 0.08 * lq ** 2 + 0.01 * lq ** 3),
                               rtol=1e-12)
    # below q_1 the cubic in q through M(0) = 0 and the first three loads
    cubic = lambda t: 0.3 * t - 0.2 * t ** 2 + 0.05 * t ** 3  # noqa: E731
    log_m = np.log(cubic(LOADS[1:]))[None, :]
    q = np.array([[0.0, 0.01, 0.1, 0.2, 0.2499]])
    np.testing.assert_allclose(_read(axis, log_m, q), cubic(q), rtol=1e-12, atol=1e-15)
    # exact at every node, NaN beyond the last load
    got = _read(axis, log_m, LOADS[None, :])
    np.testing.assert_allclose(got, np.r_[0.0, cubic(LOADS[1:])][None, :], rtol=1e-13)
    assert np.isnan(_read(axis, log_m, np.array([[LOADS[-1] * 1.01]]))).all()


def test_rows_read_their_own_loads_and_a_stopped_ray_shifts_its_stencil_back():
    axis = LoadAxis(LOADS)
    x = np.log(LOADS[1:])
    rays = np.vstack([0.5 * x, 0.5 * x + 1.0])  # M = sqrt(q), e sqrt(q)
    rays[1, 7:] = np.nan  # the second ray stopped at q = 12
    q = np.array([[3.0, 10.0, 11.9, 14.0], [3.0, 10.0, 11.9, 14.0]])
    got = _read(axis, rays, q)
    np.testing.assert_allclose(got[0], np.sqrt(q[0]), rtol=1e-12)
    # the cell (8, 12) is read from the stencil ending at 12, never past it
    np.testing.assert_allclose(got[1, :3], np.e * np.sqrt(q[1, :3]), rtol=1e-12)
    assert np.isnan(got[1, 3])
    w = axis.weights(q)
    assert w["loads"] == 10  # q = 14 reads the loads 8-20 (indices 6-9), not 24


def test_the_piecewise_cubic_reads_as_the_stencils_do_with_stopped_rays_and_node_hits():
    """evaluate (one cubic per cell and ray) against read (weights per load, the rules
    of stopped rays): equal to rounding, the same NaN, at every kind of load."""
    axis = LoadAxis(LOADS)
    rng = np.random.default_rng(1)
    x = np.log(LOADS[1:])
    n = 60
    rays = (rng.uniform(-1, 1, (n, 1)) + rng.uniform(0.3, 0.9, (n, 1)) * x
            - rng.uniform(0, 0.05, (n, 1)) * x ** 2)
    for i, stop in enumerate(rng.integers(2, LOADS.size, n)):
        if i % 3:
            rays[i, stop:] = np.nan  # stopped at LOADS[stop]
    q = np.column_stack([
        rng.uniform(0.0, LOADS[-1] * 1.05, (n, 40)),   # anywhere, beyond the last load too
        rng.choice(LOADS, (n, 8)),                      # exactly at the nodes
        rng.uniform(0.0, LOADS[1], (n, 4)),             # below q_1
        np.full((n, 1), np.nan)])
    for width in (rays.shape[1], axis.loads_for(q[:, :10]) - 1):
        want = axis.read(rays[:, :width], axis.weights(q if width == rays.shape[1] else q[:, :10]))
        got = axis.evaluate(rays[:, :width], q if width == rays.shape[1] else q[:, :10])
        np.testing.assert_array_equal(np.isnan(got), np.isnan(want))
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-15)
    assert np.isnan(got).any() and (~np.isnan(got)).any()
    assert axis.loads_for(q[:, :10]) == axis.weights(q[:, :10])["loads"]


@pytest.mark.slow
def test_closer_to_fe_than_cubic_m_in_q_where_a_thin_dermis_bends_into_a_membrane():
    """A 0.6 mm dermis over a very soft hypodermis under the 8 mm probe: the onset
    loads double from node to node while the curve turns from M ~ q to M ~ q^(1/3)."""
    spec = read_ray_spaces(SHIPPED_SPACE_DIR)[BASELINE].spec
    loads = np.asarray(spec.pressures_mbar, dtype=float)
    loads = loads[loads <= 40.0]
    skin = Skin.two_layer(spec.x1d_ref, 2.7e-4 * spec.x1d_ref, t_d=0.6, t_h=3.0)
    mesh = {"refinement": 0.5}
    ray = simulate(skin, probe=8.0, pressures_mbar=loads, mesh=mesh)
    q = np.geomspace(loads[1] * 1.05, loads[-1] * 0.95, 25)
    fe = simulate(skin, probe=8.0, pressures_mbar=np.r_[0.0, q], mesh=mesh)
    assert ray.converged and fe.converged
    m_ray = np.asarray(ray.deflection_mm, dtype=float)
    m_fe = np.asarray(fe.deflection_mm, dtype=float)[1:]
    now = _read(LoadAxis(loads), np.log(m_ray[1:])[None, :], q[None, :])[0]
    start, w = LagrangeAxis(loads).weights(q)
    before = (w * m_ray[start[:, None] + np.arange(4)]).sum(axis=1)
    err_now = np.abs(now / m_fe - 1).max()
    err_before = np.abs(before / m_fe - 1).max()
    # measured: 0.2 % against 0.8 % on the reference mesh
    assert err_now < 0.5 * err_before
    assert err_now < 3e-3
