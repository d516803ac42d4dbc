"""The space's coordinates of a skin (:class:`skinsuction.space.SpaceCoordinates`)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from skinsuction.model import Prony, Skin, simulate
from skinsuction.space import (
    SpaceCoordinates,
    default_registry,
    load,
    reference_pressure,
    similar_length,
)

COARSE = {"refinement": 0.5}


@pytest.mark.parametrize("name", sorted(default_registry()))
def test_every_cause_round_trips_through_its_coordinates(name):
    cause = default_registry()[name]
    base = Skin.two_layer(0.037, 6.1e-4, t_d=1.4, t_h=3.2, bottom="axial")
    c = 0.5 * (cause.nodes[0] + cause.nodes[-1])
    skin = cause.apply(base, c)
    coords = SpaceCoordinates.of(skin, cause)
    assert coords.coordinate == pytest.approx(c, rel=1e-12)
    assert coords.ratio == pytest.approx(6.1e-4 / 0.037, rel=1e-12)
    back = coords.skin(layers={p: base.get(p) for p in coords.layers})
    for path, value in skin.parameters().items():
        assert back.get(path) == pytest.approx(value, rel=1e-12), path
    assert back.bottom == "axial"
    # a thickness cause holds its layer in the coordinate, not in the layers
    assert set(coords.layers).isdisjoint(cause.paths)


def test_a_parameter_the_space_does_not_hold_is_refused_by_name():
    stiff = Skin.two_layer(0.05, 5e-4, x2d=0.1)
    with pytest.raises(ValueError, match="dermis.X2 = 0.1"):
        SpaceCoordinates.of(stiff)
    with pytest.raises(ValueError, match="relaxation spectrum"):
        SpaceCoordinates.of(Skin.two_layer(0.05, 5e-4, spectrum=Prony([0.5], [1.0])))
    with pytest.raises(ValueError, match="dermis over a hypodermis"):
        SpaceCoordinates.of(Skin.two_layer(0.05, 5e-4).with_layer_on_top("superficial", 0.1, 0.02))


def test_skins_of_equal_coordinates_but_the_scale_give_one_curve_in_load():
    # M(s X1d, s X1h, s X2d, s p) = M(X1d, X1h, X2d, p): the FE curves of two skins that
    # differ only in dermis.X1 coincide when read at the same load p / X1d
    stiff = default_registry()["strain_stiffening"]
    a = stiff.apply(Skin.two_layer(0.02, 4e-4, t_d=1.3), 3.0)
    b = SpaceCoordinates.of(a, stiff)
    b = SpaceCoordinates(0.05, b.ratio, b.layers, b.bottom, b.cause, b.coordinate).skin()
    p_a = np.array([0.0, 20.0, 40.0])
    p_b = reference_pressure(p_a, 0.02, 0.05)
    np.testing.assert_allclose(load(p_b, 0.05), load(p_a, 0.02), rtol=1e-14)
    ma = simulate(a, 2.0, pressures_mbar=p_a, mesh=COARSE).deflection_mm
    mb = simulate(b, 2.0, pressures_mbar=p_b, mesh=COARSE).deflection_mm
    np.testing.assert_allclose(mb, ma, rtol=1e-7, atol=1e-12)
    assert mb[-1] > 0.01  # a real dome, not two zeros


def test_similar_length_is_the_length_over_the_aperture_radius():
    assert similar_length(1.5, 6.0) == 0.5
    assert math.isclose(similar_length(0.1, 8.0), 0.025)
