"""The fast engine against FElupe's: the same residual, tangent and curves.

``engine="fast"`` replaces FElupe's general assembly by NumPy code written for
this one model (:mod:`skinsuction.model._fast`). FElupe's stays the reference:
at one displaced state, both engines must give the same residual on every DOF
and the same tangent on the free DOFs, to round-off, for every option of the
model that the fast path covers.
"""

import felupe as fem
import numpy as np
import pytest

from skinsuction.model import ParameterError, Skin, SuctionTest, simulate
from skinsuction.model._fast import FastAssembly

COARSE = {"refinement": 0.5}
PRESSURE_MBAR = 60.0
TOL = 1e-10

# (x2d, x2h, prestretch, probe_wall, probe_mm, bottom): with every element and
# quadrature, these six cases hold every pair of values of these options
X2 = (0.05, 5e-4)
CASES = [
    pytest.param(0.0, 0.0, 1.0, True, 6, "fixed", id="neo-Hooke-wall-6mm-fixed"),
    pytest.param(*X2, 1.1, False, 2, "fixed", id="X2-prestretch-2mm-fixed"),
    pytest.param(0.0, 0.0, 1.1, True, 2, "axial", id="neo-Hooke-prestretch-wall-2mm-axial"),
    pytest.param(*X2, 1.0, False, 6, "axial", id="X2-6mm-axial"),
    pytest.param(*X2, 1.0, True, 2, "free", id="X2-wall-2mm-free"),
    pytest.param(0.0, 0.0, 1.1, False, 6, "free", id="neo-Hooke-prestretch-6mm-free"),
    # three layers: a soft superficial layer with its own X2 and pre-stretch
    pytest.param(*X2, 1.05, True, 2, "fixed", id="three-layers-X2-prestretch-wall-2mm-fixed"),
]


def skin_of(case_id, x2d, x2h, prestretch, bottom):
    skin = Skin.two_layer(0.01, 1e-4, x2d=x2d, x2h=x2h, bottom=bottom, prestretch=prestretch)
    if case_id.startswith("three-layers"):
        skin = skin.with_layer_on_top("superficial", 0.3, 0.003, X2=0.02, prestretch=1.02)
    return skin


def twins(mesh, skin, probe):
    """The same model twice, by FElupe's engine and by the fast one (same mesh,
    same DOF numbering)."""
    reference = SuctionTest(skin, probe, mesh={**mesh, "engine": "felupe"})
    fast = SuctionTest(skin, probe, mesh={**mesh, "engine": "fast"})
    assert (reference.engine, fast.engine) == ("felupe", "fast")
    np.testing.assert_array_equal(reference.mesh.points, fast.mesh.points)
    np.testing.assert_array_equal(reference.dof1, fast.dof1)
    return reference, fast


def turned_onto_the_wall(model, turn_deg=100.0, seed=0):
    """A displacement field in which the skin turns about the aperture edge by
    ``turn_deg`` (past 90 degrees: the surface next to the edge goes beyond the
    probe wall ``r = a``), with a little noise; zero on the prescribed DOFs.

    Around the edge (polar radius rho, angle phi from the free surface, through
    the skin, to the glued face) each point turns by ``fade(rho) turn (1 - phi /
    pi)``: the map stays one to one (the angle grows monotonically in phi) and
    fades out to nothing at ``rho = 0.6 a``, short of the axis and the bottom.
    The noise scales with the distance to the edge and to the axis, so it
    distorts the small cells at the edge no more than the large ones.
    """
    a = model.parameters["probe_mm"] / 2
    z, r = model.mesh.points.T  # z <= 0 in the skin
    rho = np.hypot(z, r - a)
    phi = np.arctan2(np.abs(z), a - r)
    s = np.clip((rho - 0.1 * a) / (0.5 * a), 0.0, 1.0)
    fade = 1.0 - s * s * (3.0 - 2.0 * s)
    turned = phi - fade * np.radians(turn_deg) * (1.0 - phi / np.pi)
    u = np.stack([-rho * np.sin(turned) - z, a - rho * np.cos(turned) - r], axis=1)
    rng = np.random.default_rng(seed)
    u += 3e-3 * np.minimum(np.minimum(rho, r), a)[:, None] * rng.standard_normal(u.shape)
    u.reshape(-1)[model.dof0] = 0.0
    return u


def relative_difference(ours, reference):
    return np.abs(ours - reference).max() / np.abs(reference).max()


@pytest.mark.parametrize("x2d, x2h, prestretch, probe_wall, probe_mm, bottom", CASES)
@pytest.mark.parametrize("quadrature", ["reduced", "full"])
@pytest.mark.parametrize("element", ["quad8", "quad9"])
def test_fast_residual_and_tangent_are_felupes(
    element, quadrature, x2d, x2h, prestretch, probe_wall, probe_mm, bottom, request
):
    """At a displaced state under suction (the wall contact active where it is
    on), the fast residual equals FElupe's on every DOF and the fast tangent
    equals FElupe's on the free DOFs, to 1e-10 of their largest entries; the
    model's own wall penalty is FElupe's. The suction's share of both is small at
    this state (1e-4 of the residual, 1e-5 of the tangent), so it is checked on
    its own as well, to 1e-10 of itself."""
    reference, model = twins(
        {**COARSE, "element": element, "quadrature": quadrature, "probe_wall": probe_wall},
        skin_of(request.node.callspec.id.split("-", 2)[-1], x2d, x2h, prestretch, bottom),
        probe_mm,
    )
    u = turned_onto_the_wall(reference)
    for m in (reference, model):
        m.field[0].values[:] = u
        m._set_pressure(PRESSURE_MBAR)
    residual = fem.tools.fun(reference.items, reference.field)
    tangent = fem.tools.jac(reference.items, reference.field)
    assert np.all(np.isfinite(residual))  # no cell is inverted
    fast = model.fast
    assert (model._wall is None) == (not probe_wall)
    if probe_wall:
        wall = reference._wall
        radial = (reference.mesh.points + u)[wall.points, 1]
        assert np.count_nonzero(radial > probe_mm / 2) >= 1  # the contact is active
        # the fast engine sets its penalty at the first evaluation, as FElupe does
        model._residual()
        assert fast.wall_multiplier == pytest.approx(wall.multipliers.normal, rel=TOL)
        fast.wall_multiplier = wall.multipliers.normal

    ours = fast.residual(u, model._pressure)
    assert relative_difference(ours, residual) < TOL
    free = reference.dof1
    assert relative_difference(ours[free], residual[free]) < TOL

    K = fast.matrix(fast.tangent(u, model._pressure))
    rows = free[fast.order]
    K_reference = tangent.tocsr()[rows][:, rows]
    assert abs(K - K_reference).max() / abs(K_reference).max() < TOL

    # the suction alone: FElupe's pressure item, and the fast engine's change with
    # the pressure (everything else is the same arithmetic at both pressures)
    load = fem.tools.fun([reference.suction], reference.field)
    load_K = fem.tools.jac([reference.suction], reference.field).tocsr()[rows][:, rows]
    assert relative_difference(ours - fast.residual(u, 0.0), load) < TOL
    ours_load_K = K - fast.matrix(fast.tangent(u, 0.0))
    assert abs(ours_load_K - load_K).max() / abs(load_K).max() < TOL


def test_fast_curve_is_felupes():
    """A whole curve of a soft dermis (a large deflection, reached through cut-back
    increments) is the same from either engine to 1e-8, and the curve says which
    engine ran. (A failed trial increment may take a different number of
    iterations: a diverging Newton iteration amplifies round-off.)"""
    kwargs = dict(skin=Skin.two_layer(0.01, 1e-4), probe=6,
                  pressures_mbar=np.arange(0.0, 61.0, 10.0), mesh=COARSE)
    fast = simulate(**kwargs, engine="fast")
    reference = simulate(**kwargs, engine="felupe")
    assert fast.converged and reference.converged
    assert fast.info["engine"] == "fast" and reference.info["engine"] == "felupe"
    assert fast.info["mesh"]["engine"] == "fast"
    assert reference.deflection_mm[-1] > 1.0  # a third of the aperture radius
    np.testing.assert_allclose(fast.deflection_mm, reference.deflection_mm, rtol=1e-8)


def test_auto_engine_takes_the_fast_path_where_it_applies():
    """``engine="auto"`` (the default) assembles with the fast engine for the
    displacement formulation with a sharp probe edge, and with FElupe's for a
    rounded edge or the mixed formulation; asking for the fast engine where it
    does not apply is an error that names the engine."""
    params = dict(skin=Skin.two_layer(0.01, 1e-4), probe=2)
    default = SuctionTest(**params, mesh=COARSE)
    assert default.engine == "fast" and isinstance(default.fast, FastAssembly)
    rounded = {**COARSE, "corner": "grid", "edge_radius": 0.05}
    assert SuctionTest(**params, mesh=rounded).engine == "felupe"
    mixed = {**COARSE, "formulation": "mixed"}
    assert SuctionTest(**params, mesh=mixed).engine == "felupe"
    for settings in (mixed, rounded):
        with pytest.raises(ParameterError, match="engine"):
            SuctionTest(**params, mesh={**settings, "engine": "fast"})
    with pytest.raises(ParameterError, match="engine"):
        SuctionTest(**params, mesh={**COARSE, "engine": "numpy"})
