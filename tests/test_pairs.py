"""Pair spaces: two causes at once (skinsuction.space._pairs) and the ramp's second effect.

The interpolation is checked on a field that cubic Lagrange reproduces exactly
(log M cubic in each ray axis, M cubic in the load), the assembly against the
single causes' edges, and the diagnosis on FE virtual ramps of skins with two
effects (the shipped pair spaces).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from skinsuction.space import (
    BASELINE,
    CausePair,
    PairRayInterpolant,
    RayInterpolant,
    RaySpace,
    RaySpec,
    assemble_pair_space,
    default_registry,
    pair_bundles,
    pair_from_config,
    pair_rays,
    read_pair_space,
    space_causes,
)
from skinsuction.space._storage import _write_parquet

REG = default_registry()
SPEC = RaySpec([2.0, 6.0], [1e-3, 3e-3, 1e-2, 3e-2, 0.1], load_max=20000.0, load_steps=6,
               load_refine=0)


def _pair():
    return pair_from_config({"causes": ["strain_stiffening", "pre_tension"],
                             "nodes": [1.0, 1.05, 1.1, 1.2]}, REG)


def _field(probe, log_r, u1, u2, q):
    """M exactly representable: log M cubic in (log r, u1, u2), M cubic in q (M(0) = 0)."""
    g = (0.3 * log_r - 0.05 * log_r ** 2 + 0.01 * log_r ** 3 - 0.4 * u1 + 0.07 * u1 ** 2
         - 0.8 * u2 + 0.5 * u2 * u1 + 0.02 * u2 ** 3 + 0.1 * probe)
    s = q / 20000.0
    return np.exp(g) * (s + 0.3 * s ** 2 - 0.1 * s ** 3)


def _rays(cause1, nodes1, cause2, nodes2, probe):
    q = np.asarray(SPEC.pressures_mbar) / SPEC.x1d_ref
    out = np.empty((len(SPEC.ratio_nodes), len(nodes1) * len(nodes2), q.size))
    for i, r in enumerate(SPEC.ratio_nodes):
        for j1, c1 in enumerate(nodes1):
            for j2, c2 in enumerate(nodes2):
                u1 = cause1.to_axis(c1) if cause1 else 0.0
                u2 = cause2.to_axis(c2) if cause2 else 0.0
                out[i, j1 * len(nodes2) + j2] = _field(probe, math.log10(r), u1, u2, q)
    return out


def _singles(pair):
    a, b = pair.causes
    full_b = REG[b.name]
    return {
        a.name: RaySpace(a, SPEC, np.array(a.nodes),
                         {p: _rays(a, a.nodes, b, [b.neutral], p) for p in SPEC.probes_mm}),
        b.name: RaySpace(full_b, SPEC, np.array(full_b.nodes),
                         {p: _rays(a, [a.neutral], full_b, full_b.nodes, p)
                          for p in SPEC.probes_mm}),
    }


def _bundle(tmp_path, pair):
    """A bundle file of the pair's new rays, from the field."""
    q = np.asarray(SPEC.pressures_mbar) / SPEC.x1d_ref
    a, b = pair.causes
    frames = []
    for ray in pair_rays(SPEC, pair):
        m = _field(ray["probe_mm"], math.log10(ray["ratio"]), a.to_axis(ray["coordinate"]),
                   b.to_axis(ray["coordinate2"]), q)
        frames.append(pd.DataFrame({"ray_id": ray["ray_id"], "pressure_mbar":
                                    SPEC.pressures_mbar, "deflection_mm": m}))
    path = tmp_path / "bundle.parquet"
    _write_parquet(pd.concat(frames, ignore_index=True), path,
                   {"rays": {r["ray_id"]: {"converged": True} for r in pair_rays(SPEC, pair)}})
    return path


@pytest.fixture
def pair_space(tmp_path):
    pair = _pair()
    out = tmp_path / "pairs" / f"{pair.name}.parquet"
    built = assemble_pair_space([_bundle(tmp_path, pair)], _singles(pair), out, SPEC, pair)
    return built, read_pair_space(out)


def test_pair_rays_are_only_the_new_ones():
    pair = _pair()
    rays = pair_rays(SPEC, pair)
    # (8 - 1) stiffening x (4 - 1) pre-tension nodes per probe and X1h/X1d
    assert len(rays) == 7 * 3 * 5 * 2
    assert all(r["coordinate"] != 0.0 and r["coordinate2"] != 1.0 for r in rays)
    assert all("x2d" in r["params"] and "prestretch" in r["params"] for r in rays)
    bundles = pair_bundles(SPEC, {pair.name: pair}, rays_per_job=30)
    assert sorted(sum(bundles.values(), [])) == sorted(r["ray_id"] for r in rays)


def test_assembled_pair_has_the_single_causes_as_edges(pair_space):
    built, read = pair_space
    singles = _singles(_pair())
    for p in SPEC.probes_mm:
        np.testing.assert_array_equal(read.rays(p), built.rays(p))
        # the slice at lambda0 = 1 is the stiffening space, at X2d = 0 the pre-tension one
        np.testing.assert_array_equal(read.slice_second(0).rays(p),
                                      singles["strain_stiffening"].rays(p))
        full = list(REG["pre_tension"].nodes)
        np.testing.assert_array_equal(read.rays(p)[:, :4], singles["pre_tension"].rays(p)[
            :, [full.index(c) for c in (1.0, 1.05, 1.1, 1.2)]])
    assert space_causes(read) == (REG["strain_stiffening"], read.second)
    assert read.name == "strain_stiffening_and_pre_tension"


def test_pair_interpolation_is_exact_on_a_cubic_field(pair_space):
    _, space = pair_space
    rng = np.random.default_rng(3)
    p = np.array([0.0, 20.0, 55.0, 100.0, 180.0])
    a, b = space.pair.causes
    n = 200
    theta = np.column_stack([
        rng.uniform(-1.8, -0.5, n), rng.uniform(-3, -1, n),
        rng.uniform(a.axis_nodes[0], a.axis_nodes[-1], n),
        rng.uniform(b.axis_nodes[0], b.axis_nodes[-1], n)])
    for probe in SPEC.probes_mm:
        f = PairRayInterpolant(space, probe, p)
        got = f(theta)
        x1d = 10.0 ** theta[:, 0]
        q = p[None, :] / x1d[:, None]
        want = _field(probe, theta[:, 1:2], theta[:, 2:3], theta[:, 3:4], q)
        ok = q <= SPEC.load_max
        np.testing.assert_allclose(got[ok], want[ok], rtol=1e-9, atol=1e-12)
        assert np.isnan(got[~ok]).all()
        # the pair at lambda0 = 1 is the stiffening model; no extrapolation beyond the nodes
        single = RayInterpolant(space.slice_second(0), probe, p)(theta[:, :3])
        at_neutral = f(np.column_stack([theta[:, :3], np.full(n, b.to_axis(1.0))]))
        np.testing.assert_allclose(at_neutral, single, rtol=1e-12, equal_nan=True)
        outside = f(np.column_stack([theta[:, :3], np.full(n, b.axis_nodes[-1] + 0.01)]))
        assert np.isnan(outside[:, p > 0]).all()  # M(0) = 0 everywhere, as for one cause
    assert list(f.lower[2:]) == [a.axis_nodes[0], b.axis_nodes[0]]


@pytest.mark.parametrize("entry, message", [
    ({"causes": ["strain_stiffening"]}, "two causes"),
    ({"causes": ["strain_stiffening", "creep"], "nodes": [1, 2, 3, 4]}, "no cause 'creep'"),
    ({"causes": ["pre_tension", "pre_tension"], "nodes": [1, 1.05, 1.1, 1.2]}, "must differ"),
    ({"causes": ["strain_stiffening", "pre_tension"], "nodes": [1.0, 1.05, 1.1]}, "at least 4"),
    ({"causes": ["strain_stiffening", "pre_tension"], "nodes": [1.0, 1.05, 1.1, 1.3]},
     "not nodes of"),
    ({"causes": ["strain_stiffening", "pre_tension"], "nodes": [1.05, 1.1, 1.15, 1.2]},
     "neutral"),
])
def test_bad_pair_configuration_names_the_key(entry, message):
    with pytest.raises(ValueError, match=message) as err:
        pair_from_config(entry, REG, "scale_free_space.pairs[0]")
    assert "scale_free_space.pairs[0]" in str(err.value)


def test_pair_assembly_names_a_missing_ray(tmp_path):
    pair = _pair()
    with pytest.raises(ValueError, match="missing from the inputs"):
        assemble_pair_space([], _singles(pair), tmp_path / "x.parquet", SPEC, pair)
    singles = _singles(pair)
    del singles["pre_tension"]
    with pytest.raises(ValueError, match="pre_tension space is needed"):
        assemble_pair_space([], singles, tmp_path / "x.parquet", SPEC, pair)


def test_pair_round_trips_through_its_dict():
    pair = _pair()
    assert CausePair.from_dict(pair.to_dict()) == pair
    assert BASELINE not in pair.name
