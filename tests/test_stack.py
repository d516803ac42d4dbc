"""Any stack of layers: the skin's description, and the forward model of one to four
layers verified with a third, superficial one (docs/model.md#a-stack-of-layers).

The checks against independent facts: splitting a layer into two identical ones
changes nothing (to 1e-9, on the same mesh); one thick layer on a fixed bottom
is the half-space aspiration result of small-strain theory; M converges under
nested refinement for a superficial layer down to 0.05 mm; geometric similarity
holds exactly for three layers; and each layer relaxes with its own spectrum.
(The fast assembly against FElupe's for three layers: tests/test_fast.py.)
"""

import json

import numpy as np
import pytest

from skinsuction.model import (
    Layer, MeshSettings, ParameterError, Probe, Prony, Ramp, Skin, SuctionTest, simulate,
)

COARSE = {"refinement": 0.5}
PAPER = Skin.two_layer(0.08, 4.1e-4)


def superficial(skin=PAPER, thickness=0.1, x1=0.02, **kw):
    """``skin`` under a superficial layer, the dermis thinner by as much (so the
    dermis and the new layer keep the paper's 1 mm)."""
    top = skin.with_layer_on_top("superficial", thickness, x1, **kw)
    return top.replace({"dermis.thickness": skin["dermis"].thickness - thickness})


# ---------------------------------------------------------------- the skin itself
def test_a_skin_round_trips_through_json_and_yaml(tmp_path):
    skin = superficial(Skin.two_layer(0.05, 3e-4, x2d=0.4, bottom="axial", prestretch=1.02,
                                      spectrum={"dermis": Prony([0.5, 1.0], [0.05, 2.0])}))
    assert Skin.from_dict(json.loads(skin.to_json())) == skin
    for name in ("skin.yaml", "skin.json"):
        assert Skin.read(skin.write(tmp_path / name)) == skin
    assert skin.get("dermis.spectrum.tau_s[1]") == 2.0
    assert skin.get("superficial.prestretch") == 1.02  # a new top layer takes its neighbour's


def test_parameter_paths_name_every_value_and_replace_one():
    skin = Skin.two_layer(0.05, 3e-4, spectrum=Prony([0.5], [0.1]))
    paths = skin.parameters()
    assert list(paths)[:4] == ["dermis.thickness", "dermis.X1", "dermis.X2", "dermis.prestretch"]
    assert paths["hypodermis.spectrum.g[0]"] == 0.5
    changed = skin.replace({"hypodermis.thickness": 4.0, "dermis.spectrum.g[0]": 0.7})
    assert changed.get("hypodermis.thickness") == 4.0 and changed.get("dermis.spectrum.g[0]") == 0.7
    assert changed.get("hypodermis.spectrum.g[0]") == 0.5 and skin.get("hypodermis.thickness") == 1.0
    for bad, match in [("dermis.E", "not a parameter path"), ("fat.X1", "no layer 'fat'"),
                       ("dermis.spectrum.g[3]", "1 spectrum terms")]:
        with pytest.raises(ParameterError, match=match):
            skin.get(bad)


@pytest.mark.parametrize("text, match", [
    ("layers: [{name: dermis, thickness: 1, X1: 80000}]", r"dermis\.X1 = 80000 .*units"),
    ("layers: [{name: dermis, thickness: 1}]", r"layers\[0\]: missing \['X1'\]"),
    ("layers: [{name: dermis, thickness: 1, X1: 0.1, E: 3}]", r"layers\[0\]: unknown key"),
    ("layers: [{name: d, thickness: 1, X1: 0.1}, {name: d, thickness: 1, X1: 0.1}]", "distinct"),
    ("layers: []\n", "1 to 4 layers"),
    ("layers: [{name: dermis, thickness: 1, X1: 0.1}]\nbottom: glued", "bottom"),
    ("skin: [1, 2", "not valid YAML"),
])
def test_a_bad_skin_file_names_the_file_and_the_key(tmp_path, text, match):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(ParameterError, match=match) as err:
        Skin.read(path)
    assert str(path) in str(err.value)


def test_probe_and_ramp():
    assert Probe(8).radius_mm == 4.0
    assert Ramp(450, 50).pressures_mbar[[0, -1]].tolist() == [0.0, 450.0]
    with pytest.raises(ParameterError, match="aperture"):
        Probe(-2)
    assert PAPER.two_layer_values()["x1h"] == 4.1e-4
    with pytest.raises(ParameterError, match="superficial"):  # what needs two layers says so
        superficial().two_layer_values()


def test_every_curve_records_its_skin():
    skin = superficial()
    curve = simulate(skin, 2, pressures_mbar=[0, 20], mesh=COARSE)
    assert Skin.from_dict(curve.info["skin"]) == skin and curve.info["probe_mm"] == 2.0


# ------------------------------------------------------------ the forward model
@pytest.mark.parametrize("probe_mm", [2, 6])
def test_a_layer_split_in_two_identical_ones_changes_nothing(probe_mm):
    """A superficial layer with the dermis's own law and pre-stretch is the two-layer
    model on the same mesh (the split's depth a node line of both), to 1e-9."""
    two = Skin.two_layer(0.03, 5e-4, x2d=0.2, prestretch=1.02)
    three = superficial(two, 0.1, 0.03, X2=0.2)
    p = [0.0, 30.0, 60.0]
    split = simulate(three, probe_mm, pressures_mbar=p, mesh=COARSE)
    whole = simulate(two, probe_mm, pressures_mbar=p, mesh={**COARSE, "node_lines_mm": [0.1]})
    assert split.converged and whole.converged and split.dofs == whole.dofs
    np.testing.assert_allclose(split.deflection_mm, whole.deflection_mm, rtol=1e-9, atol=0)
    # and a different top layer does change it
    softer = simulate(three.replace({"superficial.X1": 0.01}), probe_mm, pressures_mbar=p,
                      mesh=COARSE)
    assert softer.deflection_mm[-1] > 1.01 * whole.deflection_mm[-1]


def test_one_thick_layer_on_a_fixed_bottom_is_the_half_space_aspiration_result():
    """Theret et al. (1988), small strain, incompressible half-space under a
    pipette: M = 3 a p Phi / (2 pi E) with Phi = 2.0 ... 2.1."""
    a, x1, p_mbar = 1.0, 1.0, 1.0
    skin = Skin((Layer("dermis", 10.0, x1),))
    curve = simulate(skin, 2 * a, pressures_mbar=[0, p_mbar])
    young = 2 * (2 * x1) * (1 + 0.49)
    phi = curve.deflection_mm[-1] * 2 * np.pi * young / (3 * a * p_mbar * 1e-4)
    assert 2.0 <= phi <= 2.1


@pytest.mark.parametrize("thickness", [0.3, 0.1, 0.05])
def test_mesh_convergence_over_a_thin_superficial_layer(thickness):
    """Nested refinements h, h/2, h/3 under the 2 mm probe, a superficial layer four
    times softer than the dermis: M increases monotonically at an observed order
    above 1/2 (about 1, the glued edge is singular), and the default mesh is within
    1 % of the extrapolated limit even for a 0.05 mm layer."""
    skin = superficial(thickness=thickness, x1=0.02)
    M = [simulate(skin, 2, pressures_mbar=[0, 50, 100], mesh={"refinement": k}).deflection_mm[-1]
         for k in (1, 2, 3)]
    assert M[0] < M[1] < M[2]
    ratio = (M[1] - M[0]) / (M[2] - M[1])
    q_half = (1 - 2**-0.5) / (2**-0.5 - 3**-0.5)
    assert ratio > q_half
    q = 1.0  # the order the ratios show (3.4-3.9 for q = 1.1-1.3; q = 1 is the safe side)
    limit = M[2] + (M[2] - M[1]) / ((3 / 2) ** q - 1)
    assert abs(limit - M[0]) / limit < 0.01


@pytest.mark.parametrize("length_scale", [2 / 3, 4 / 3])
def test_geometric_similarity_of_three_layers(length_scale):
    """Every length (aperture, each layer, the mesh) scaled by s scales M by s."""
    skin = superficial(Skin.two_layer(0.02, 4e-4, x2d=0.01, t_d=1.2, t_h=3.0), 0.15, 0.005)
    p = [0.0, 20.0, 40.0]
    base = simulate(skin, 6.0, pressures_mbar=p, mesh=COARSE)
    s = length_scale
    scaled = skin.replace({f"{n}.thickness": s * skin[n].thickness for n in skin.names})
    other = simulate(scaled, s * 6.0, pressures_mbar=p, mesh=COARSE)
    assert base.converged and other.converged and other.dofs == base.dofs
    np.testing.assert_allclose(other.deflection_mm, s * base.deflection_mm, rtol=1e-10,
                               atol=1e-14)


def test_four_layers_run_and_five_are_refused():
    skin = superficial().with_layer_on_top("stratum", 0.02, 0.5)
    model = SuctionTest(skin, 2, COARSE)
    assert model.layer_names == ("stratum", "superficial", "dermis", "hypodermis")
    assert sorted(set(model.layer.tolist())) == [0, 1, 2, 3]
    assert model.run([0.0, 10.0]).converged
    with pytest.raises(ParameterError, match="1 to 4 layers"):
        skin.with_layer_on_top("film", 0.01, 0.5)


def test_each_layer_relaxes_with_its_own_spectrum():
    """A spectrum on the superficial layer alone: right after a fast rise the skin
    answers as the elastic stack whose superficial X1 is ``X1 (1 + g)`` (the
    instantaneous moduli), and long after as the long-time stack."""
    from skinsuction.viscoelastic import simulate_history

    g, tau = 3.0, 0.5
    skin = superficial(thickness=0.3, x1=0.01)
    layers = list(skin.layers)
    layers[0] = Layer("superficial", 0.3, 0.01, spectrum=Prony([g], [tau]))
    skin = Skin(tuple(layers), skin.bottom)
    p = 40.0
    history = simulate_history(skin, [0.0, 1e-5, 1e-4, 50.0], [0.0, p, p, p], probe=2,
                               mesh=COARSE, max_step_s=5.0)
    instantaneous = simulate(skin.replace({"superficial.X1": 0.01 * (1 + g)}), 2,
                             pressures_mbar=[0, p], mesh=COARSE).deflection_mm[-1]
    long_time = simulate(skin, 2, pressures_mbar=[0, p], mesh=COARSE).deflection_mm[-1]
    assert history.converged
    assert history.deflection_mm[1] == pytest.approx(instantaneous, rel=1e-3)
    assert history.deflection_mm[-1] == pytest.approx(long_time, rel=1e-3)
    assert instantaneous < 0.9 * long_time


def test_node_lines_outside_the_stack_are_refused():
    with pytest.raises(ParameterError, match="node_lines_mm"):
        simulate(PAPER, 2, mesh=MeshSettings(node_lines_mm=(2.5,)))


def test_a_cause_frees_named_paths_and_sets_them_as_its_grid_keyword_does():
    """Each registry cause's paths on a skin are the same model as its two-layer
    grid keyword (what the spaces solve): one description, two ways in."""
    from skinsuction.space import default_registry

    base = dict(x1d=0.04, x1h=5e-4)
    for cause in default_registry().values():
        for coordinate in (cause.nodes[0], cause.nodes[-1]):
            by_paths = cause.apply(Skin.two_layer(**base), coordinate)
            by_keyword = Skin.two_layer(**base, **cause.simulate_keywords(coordinate, 0.04))
            assert by_paths == by_keyword, cause.name
            assert all(p.split(".")[0] in by_paths.names for p in cause.paths)
