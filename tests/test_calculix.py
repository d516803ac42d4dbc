"""The model against CalculiX: the same mesh as an Abaqus deck, solved by ccx.

:func:`skinsuction.model.inp_deck` writes a built model (its mesh, layers,
boundary conditions, follower suction) as a plain Abaqus input deck; CalculiX
(``ccx``, an independent FE code) solves it with its own elements (CAX8R,
expanded to 20-node bricks), material laws (NEO HOOKE, REDUCED POLYNOMIAL) and
Newton solver. The apex deflection must agree with this model's on the same mesh
to 0.3 % (same element family, so only the codes differ): the reference skin
under the 2 and 6 mm probes, a stiff and a soft corner of the space, X2 > 0, and
three layers. The probe wall is off on both sides (the deck omits it). One test
runs the deck at two nested meshes and sees CalculiX approach the mesh limit.

The ccx tests skip when ``ccx`` is not on PATH, unless ``SKINSUCTION_REQUIRE_CCX=1``
(as in ``.ci/run``): then a missing ccx fails them. The deck's text and the
refusals are tested without ccx.
"""

import os
import re
import shutil

import numpy as np
import pytest

import skinsuction
from skinsuction.model import ParameterError, Skin, SuctionTest
from skinsuction.model._inp import ABAQUS_ORDER  # the node order the deck writes
from skinsuction.model import (
    CalculixError,
    inp_deck,
    read_dat,
    run_calculix,
    write_inp,
)

COARSE = {"refinement": 0.5, "probe_wall": False}
REFERENCE = Skin.two_layer(0.08, 4.1e-4)
TOLERANCE = 3e-3  # relative, on M at every output pressure


@pytest.fixture
def ccx():
    """The ccx executable, or a skip (a failure with SKINSUCTION_REQUIRE_CCX=1)."""
    exe = shutil.which("ccx")
    if exe is None:
        if os.environ.get("SKINSUCTION_REQUIRE_CCX") == "1":
            pytest.fail("SKINSUCTION_REQUIRE_CCX=1 but CalculiX (ccx) is not on PATH")
        pytest.skip("CalculiX (ccx) is not on PATH")
    return exe


def both(skin, probe, pressures, tmp_path, mesh=COARSE):
    """M(p) of this model and of CalculiX on the same mesh."""
    ours = SuctionTest(skin, probe, mesh).run(pressures)
    assert ours.converged, ours.reason
    deck = inp_deck(SuctionTest(skin, probe, mesh), pressures)
    _, theirs = run_calculix(deck, tmp_path, pressures_mbar=pressures)
    return ours.deflection_mm, theirs


CASES = [
    # the reference skin (X1d 0.08, X1h 4.1e-4 MPa, 1 + 1 mm, fixed bottom)
    pytest.param(REFERENCE, 2.0, [0, 50, 100], id="reference-2mm"),
    pytest.param(REFERENCE, 6.0, [0, 50, 100], id="reference-6mm"),
    # the stiff corner of the space: both layers 0.3 MPa (M of a few um)
    pytest.param(Skin.two_layer(0.3, 0.3), 2.0, [0, 100], id="stiff-2mm"),
    pytest.param(Skin.two_layer(0.3, 0.3), 6.0, [0, 100], id="stiff-6mm"),
    # the soft corner: X1d 0.007, X1h 1e-5 MPa; under 6 mm the dome reaches 1 mm
    # at 20 mbar (without the wall the model stops near 90 mbar)
    pytest.param(Skin.two_layer(0.007, 1e-5), 2.0, [0, 50, 100], id="soft-2mm"),
    pytest.param(Skin.two_layer(0.007, 1e-5), 6.0, [0, 10, 20], id="soft-6mm"),
    # X2 > 0 in both layers: *HYPERELASTIC, REDUCED POLYNOMIAL, N=2
    pytest.param(Skin.two_layer(0.08, 4.1e-4, x2d=0.5, x2h=0.01), 6.0, [0, 100],
                 id="X2-6mm"),
    # the other bottom conditions
    pytest.param(Skin.two_layer(0.08, 4.1e-4, bottom="axial"), 6.0, [0, 100],
                 id="axial-bottom-6mm"),
    pytest.param(Skin.two_layer(0.08, 4.1e-4, bottom="free"), 2.0, [0, 100],
                 id="free-bottom-2mm"),
    # three layers: a thin stiffer superficial layer with X2 over the reference skin
    pytest.param(REFERENCE.with_layer_on_top("superficial", 0.1, 0.2, X2=0.5), 6.0,
                 [0, 100], id="three-layers-6mm"),
]


@pytest.mark.parametrize("skin, probe, pressures", CASES)
def test_calculix_agrees_on_the_same_mesh(ccx, tmp_path, skin, probe, pressures):
    ours, theirs = both(skin, probe, pressures, tmp_path)
    assert theirs[0] == 0.0
    assert np.all(theirs[1:] > 0)
    np.testing.assert_allclose(theirs[1:], ours[1:], rtol=TOLERANCE)


def test_calculix_agrees_on_the_grid_corner(ccx, tmp_path):
    # the grid corner (no collapsed cells) under the reference skin
    mesh = {**COARSE, "corner": "grid"}
    ours, theirs = both(REFERENCE, 6.0, [0, 100], tmp_path, mesh)
    np.testing.assert_allclose(theirs[1:], ours[1:], rtol=TOLERANCE)


def test_calculix_agrees_under_full_integration(ccx, tmp_path):
    # quadrature "full": CAX8 (3 x 3 Gauss points) against the model's 3 x 3
    mesh = {**COARSE, "quadrature": "full"}
    deck = inp_deck(SuctionTest(REFERENCE, 2.0, mesh), [0, 100])
    assert "TYPE=CAX8," in deck and "CAX8R" not in deck
    ours, theirs = both(REFERENCE, 2.0, [0, 100], tmp_path, mesh)
    np.testing.assert_allclose(theirs[1:], ours[1:], rtol=TOLERANCE)


@pytest.mark.slow
def test_calculix_converges_with_the_mesh(ccx, tmp_path):
    # the same deck on two nested meshes (every element split in four): CalculiX
    # approaches this model's mesh limit (0.03032 mm, docs/model.md) from below,
    # and agrees with the model on each mesh
    limit = 0.03032
    errors = []
    for refinement in (1, 2):
        mesh = {"refinement": refinement, "probe_wall": False}
        ours, theirs = both(REFERENCE, 2.0, [0, 100], tmp_path / str(refinement), mesh)
        np.testing.assert_allclose(theirs[1], ours[1], rtol=TOLERANCE)
        errors.append(limit - theirs[1])
    assert 0 < errors[1] < 0.5 * errors[0], errors


def test_missing_ccx_is_a_clear_error(tmp_path):
    deck = inp_deck(SuctionTest(REFERENCE, 2.0, COARSE), [0, 100])
    with pytest.raises(CalculixError, match="not on PATH"):
        run_calculix(deck, tmp_path, ccx=str(tmp_path / "no-such-ccx"))


def test_a_failed_run_names_its_files(ccx, tmp_path):
    deck = inp_deck(SuctionTest(REFERENCE, 2.0, COARSE), [0, 100])
    broken = deck.replace("*HYPERELASTIC, NEO HOOKE", "*HYPERELASTIC, NO SUCH LAW", 1)
    with pytest.raises(CalculixError, match=r"suction\.sta.*suction\.dat"):
        run_calculix(broken, tmp_path)


# -------------------------------------------------------------- the deck's text

def deck_of(skin=REFERENCE, probe=2.0, mesh=COARSE, pressures=(0, 50, 100), **kwargs):
    model = SuctionTest(skin, probe, mesh)
    return model, inp_deck(model, pressures, **kwargs)


def blocks(deck):
    """``{keyword line: [data lines]}`` of a deck (first occurrence of each)."""
    out, key = {}, None
    for line in deck.splitlines():
        if line.startswith("**"):
            continue
        if line.startswith("*"):
            key = line
            out.setdefault(key, [])
        elif key is not None and key in out:
            out[key].append(line)
    return out


def ids(lines):
    return [int(v) for line in lines for v in line.split(",") if v.strip()]


def test_deck_has_the_models_elements_layers_and_materials():
    model, deck = deck_of()
    b = blocks(deck)
    dermis = b["*ELEMENT, TYPE=CAX8R, ELSET=DERMIS"]
    hypodermis = b["*ELEMENT, TYPE=CAX8R, ELSET=HYPODERMIS"]
    assert len(dermis) == np.sum(model.layer == 0)
    assert len(hypodermis) == np.sum(model.layer == 1)
    assert len(dermis) + len(hypodermis) == len(model.mesh.cells)
    # connectivity: the model's cells in Abaqus's order, 1-based
    rows = {int(line.split(",")[0]): [int(v) for v in line.split(",")[1:]]
            for line in dermis + hypodermis}
    for e, cell in enumerate(model.mesh.cells):
        assert rows[e + 1] == (cell[ABAQUS_ORDER] + 1).tolist()
    # nodes: every point of a cell, at x = r, y = z
    nodes = {int(line.split(",")[0]): [float(v) for v in line.split(",")[1:]]
             for line in b["*NODE, NSET=NALL"]}
    assert len(nodes) == len(np.unique(model.mesh.cells))
    for n, (x, y) in nodes.items():
        assert (y, x) == pytest.approx(tuple(model.mesh.points[n - 1]), abs=1e-12)
    # one material per layer, neo-Hookean with C10 = X1, D1 = 2/K (in Pa)
    assert deck.count("*MATERIAL") == 2 and deck.count("*HYPERELASTIC, NEO HOOKE") == 2
    c10, d1 = [float(v) for v in b["*HYPERELASTIC, NEO HOOKE"][0].split(",")]
    assert c10 == pytest.approx(0.08e6)
    assert d1 == pytest.approx(2 / (model.solid.umat.bulk[model.layer == 0][0] * 1e6))
    assert "*SOLID SECTION, ELSET=HYPODERMIS, MATERIAL=HYPODERMIS" in deck


def test_deck_elements_are_anticlockwise():
    # positive Jacobian: corners anticlockwise in (x = r, y = z), collapsed ones too
    model, deck = deck_of(probe=6.0)
    b = blocks(deck)
    nodes = {int(line.split(",")[0]): [float(v) for v in line.split(",")[1:]]
             for line in b["*NODE, NSET=NALL"]}
    collapsed = 0
    for line in b["*ELEMENT, TYPE=CAX8R, ELSET=DERMIS"]:
        corners = np.array([nodes[int(v)] for v in line.split(",")[1:5]])
        x, y = corners.T
        assert 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) > 0
        collapsed += len(set(line.split(",")[1:5])) < 4
    assert collapsed > 0  # the fan's innermost ring, exported as it is


def test_deck_boundary_sets_are_the_models():
    model, deck = deck_of()
    b = blocks(deck)
    used = np.zeros(model.mesh.npoints, bool)
    used[model.mesh.cells.ravel()] = True
    for key, boundary in model.boundaries.items():
        for col, dof in ((1, 1), (0, 2)):
            expect = np.flatnonzero(boundary.mask[:, col] & used) + 1
            name = f"*NSET, NSET={key.upper()}_U{dof}"
            if len(expect):
                assert sorted(ids(b[name])) == expect.tolist()
                assert f"{key.upper()}_U{dof}, {dof}, {dof}" in b["*BOUNDARY"]
            else:
                assert name not in b
    # the axis is fixed radially only; the glued face and the fixed bottom both ways
    assert "*NSET, NSET=AXIS_U2" not in b
    assert len(ids(b["*NSET, NSET=GLUED_U1"])) == len(ids(b["*NSET, NSET=GLUED_U2"]))
    assert ids(b["*NSET, NSET=APEX"]) == [model.apex + 1]


def test_deck_bottom_conditions():
    _, axial = deck_of(Skin.two_layer(0.08, 4.1e-4, bottom="axial"))
    assert "BOTTOM_U2, 2, 2" in axial and "BOTTOM_U1" not in axial
    _, free = deck_of(Skin.two_layer(0.08, 4.1e-4, bottom="free"))
    assert "BOTTOM" not in free


def test_deck_suction_faces_cover_the_aperture():
    model, deck = deck_of(probe=6.0)
    b = blocks(deck)
    loaded = {k: ids(lines) for k, lines in b.items() if k.startswith("*ELSET, ELSET=SUCTION_P")}
    total = sum(len(v) for v in loaded.values())
    # the loaded faces' nodes are exactly the surface nodes 0 <= r <= a (the fan's
    # collapsed edges, of zero length, carry no load and are left out)
    nodes = {int(line.split(",")[0]): [float(v) for v in line.split(",")[1:]]
             for line in b["*NODE, NSET=NALL"]}
    elements = {int(line.split(",")[0]): [int(v) for v in line.split(",")[1:]]
                for k, lines in b.items() if k.startswith("*ELEMENT") for line in lines}
    on_faces = set()
    for key, elems in loaded.items():
        face = int(key[-1])
        for e in elems:
            nn = elements[e]
            on_faces |= {nn[face - 1], nn[3 + face], nn[face % 4]}
    surface = {n for n, (x, y) in nodes.items() if abs(y) < 1e-12 and x <= 3.0 + 1e-9}
    assert on_faces <= surface
    assert all(nodes[n][0] == 3.0 for n in surface - on_faces)  # the edge's duplicates
    assert total == (len(on_faces) - 1) // 2
    assert max(nodes[n][0] for n in on_faces) == 3.0
    # one *DLOAD per step, -p (suction) in Pa: 1 mbar = 100 Pa
    loads = re.findall(r"SUCTION_P(\d), P\1, (\S+)", deck)
    assert {float(v) for _, v in loads} == {-5000.0, -10000.0}


def test_deck_steps_hit_every_pressure():
    _, deck = deck_of(pressures=[0, 2, 10, 100], max_increment_mbar=10)
    assert deck.count("*STEP, NLGEOM=YES") == 3
    assert deck.count("*END STEP") == 3
    static = re.findall(r"\*STATIC\n(.*)\n", deck)
    # initial increment, step time (= the pressure increment), minimum, maximum
    assert [[float(v) for v in line.split(",")] for line in static] == [
        [2.0, 2.0, 2e-6, 2.0], [8.0, 8.0, 8e-6, 8.0], [10.0, 90.0, 9e-5, 10.0]]
    assert deck.count("*NODE PRINT, NSET=APEX") == 3


def test_deck_units():
    _, pa = deck_of(pressures=[0, 100])
    _, mpa = deck_of(pressures=[0, 100], stress_unit="MPa")
    assert "SUCTION_P" in pa and re.search(r"P\d, -10000\n", pa)
    assert re.search(r"P\d, -0.01\n", mpa)
    c10 = blocks(mpa)["*HYPERELASTIC, NEO HOOKE"][0].split(",")[0]
    assert float(c10) == pytest.approx(0.08)
    with pytest.raises(ParameterError, match="stress_unit"):
        deck_of(stress_unit="psi")


def test_deck_X2_is_the_reduced_polynomial():
    _, deck = deck_of(Skin.two_layer(0.08, 4.1e-4, x2d=0.5))
    b = blocks(deck)
    assert deck.count("*HYPERELASTIC, REDUCED POLYNOMIAL, N=2") == 1
    assert deck.count("*HYPERELASTIC, NEO HOOKE") == 1
    c10, c20, d1, d2 = [float(v) for v in b["*HYPERELASTIC, REDUCED POLYNOMIAL, N=2"][0].split(",")]
    assert (c10, c20) == pytest.approx((0.08e6, 0.5e6))
    assert d2 >= 1e30  # no (J - 1)^4 term: CalculiX divides by D2


def test_deck_three_layers_get_three_sets():
    skin = REFERENCE.with_layer_on_top("superficial", 0.1, 0.2, X2=0.5)
    model, deck = deck_of(skin)
    for k, name in enumerate(("SUPERFICIAL", "DERMIS", "HYPODERMIS")):
        lines = blocks(deck)[f"*ELEMENT, TYPE=CAX8R, ELSET={name}"]
        assert len(lines) == np.sum(model.layer == k)
        assert f"*MATERIAL, NAME={name}" in deck


def test_deck_is_plain_abaqus_and_says_what_it_omits():
    _, deck = deck_of(mesh={"refinement": 0.5})  # probe wall on: left out, said so
    keywords = {line.split(",")[0] for line in deck.splitlines()
                if line.startswith("*") and not line.startswith("**")}
    assert keywords == {"*HEADING", "*NODE", "*ELEMENT", "*SOLID SECTION", "*MATERIAL",
                        "*HYPERELASTIC", "*NSET", "*ELSET", "*BOUNDARY", "*STEP",
                        "*STATIC", "*CONTROLS", "*DLOAD", "*NODE PRINT", "*END STEP"}
    assert "OMITTED: the frictionless rigid probe wall" in deck
    assert f"skinsuction {skinsuction.__version__}" in deck
    assert all(len(line) <= 256 for line in deck.splitlines())
    deck.encode("ascii")
    # numbers fit CalculiX's 20-character fields (the line after *HEADING is a title)
    lines = deck.splitlines()
    data = [v for before, line in zip(lines, lines[1:])
            if not line.startswith("*") and before != "*HEADING" for v in line.split(",")]
    assert max(len(v.strip()) for v in data) <= 20


def test_write_inp_is_atomic(tmp_path):
    model = SuctionTest(REFERENCE, 2.0, COARSE)
    path = write_inp(model, tmp_path / "suction.inp", [0, 100])
    assert path.read_text() == inp_deck(model, [0, 100])
    assert [p.name for p in tmp_path.iterdir()] == ["suction.inp"]
    with pytest.raises(ParameterError):
        write_inp(model, tmp_path / "bad.inp", [10, 100])
    assert [p.name for p in tmp_path.iterdir()] == ["suction.inp"]


@pytest.mark.parametrize("skin, mesh, match", [
    (REFERENCE, {"formulation": "mixed"}, "displacement formulation"),
    (Skin.two_layer(0.08, 4.1e-4, prestretch=1.05), {}, "pre-stretch"),
    (REFERENCE, {"corner": "grid", "edge_radius": 0.1}, "rounded probe edge"),
    (REFERENCE, {"element": "quad9"}, "quad8"),
])
def test_deck_refuses_what_it_cannot_carry(skin, mesh, match):
    model = SuctionTest(skin, 2.0, {**COARSE, **mesh})
    with pytest.raises(ParameterError, match=match):
        inp_deck(model, [0, 100])


@pytest.mark.parametrize("pressures", [[10, 100], [0, 50, 50], [0], [0, -10]])
def test_deck_refuses_bad_pressures(pressures):
    with pytest.raises(ParameterError, match="pressures"):
        deck_of(pressures=pressures)


def test_read_dat(tmp_path):
    dat = tmp_path / "x.dat"
    dat.write_text(
        "\n displacements (vx,vy,vz) for set APEX and time  0.2500000E+02\n\n"
        "       219  0.000000E+00  7.541022E-03  0.000000E+00\n"
        "\n displacements (vx,vy,vz) for set APEX and time  0.5000000E+02\n\n"
        "       219  1.000000E-09  1.507203E-02  0.000000E+00\n")
    t, u = read_dat(dat)
    assert t.tolist() == [25.0, 50.0] and u.tolist() == [7.541022e-3, 1.507203e-2]
