"""The rays' load tail: 500 mbar on soft skin at a few load nodes beyond the even steps.

The default space's rays take 48 even steps to p/X1d = 20 000 mbar/MPa and a tail of
16 steps even in log to 71 500 (500 mbar at X1d = 0.007 MPa).  Checked here: the
nodes, the specification's round trip (spaces built before the tail read alike),
the rays on demand stopping where the tail starts (as the shipped geometry spaces),
and, against direct FE runs off the nodes, the space's read in the tail.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from skinsuction.space import OnDemandRays, RaySpec, build_ray_spaces

ROOT = Path(__file__).resolve().parents[1]


def _tailed(**kw):
    # the default space's fallback mesh: at 500 mbar the default element stops first
    fallback = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())[
        "scale_free_space"]["mesh_fallback"]
    base = dict(probes_mm=[2], ratio_nodes=[0.25, 0.5, 1.0, 2.0], load_max=71500.0,
                load_steps=12, load_refine=2, load_tail_from=20000.0, load_tail_steps=8,
                fallback=fallback)
    return RaySpec(**{**base, **kw})


def test_the_tail_is_even_in_log_after_the_even_steps_and_the_onset_is_theirs():
    spec = _tailed()
    q = spec.load_nodes
    even, tail = q[q <= 20000.0], q[q > 20000.0]
    # 12 even steps (13 nodes) and 2 onset nodes below the first one
    assert len(even) == 13 + 2 and np.isclose(even[-1], 20000.0)
    assert np.allclose(spec.onset_loads, [20000 / 12 / 4, 20000 / 12 / 2])
    assert len(tail) == 8 and np.isclose(tail[-1], 71500.0)
    assert np.allclose(np.diff(np.log(np.concatenate([[20000.0], tail]))),
                       np.log(71500 / 20000) / 8)
    # the reach: 500 mbar down to X1d = 0.007 MPa
    assert spec.x1d_lower(500.0) == pytest.approx(500 / 71500) and 500 / 71500 < 0.007


def test_without_the_tail_the_rays_are_those_of_a_space_built_before_it():
    spec = _tailed()
    flat = spec.untailed()
    assert flat.load_max == 20000.0 and flat.load_tail_steps == 0
    assert np.allclose(flat.load_nodes, spec.load_nodes[spec.load_nodes <= 20000.0])
    before = RaySpec([2], [0.25, 0.5, 1.0, 2.0], load_max=20000.0, load_steps=12,
                     load_refine=2, fallback=spec.fallback)
    assert flat.to_dict() == before.to_dict()  # no tail keys: older files compare equal
    assert "load_tail_from" not in before.to_dict()
    assert RaySpec(**spec.to_dict()) == spec
    assert flat.untailed() is flat


@pytest.mark.parametrize("bad", [dict(load_tail_from=80000.0), dict(load_tail_from=0.0),
                                 dict(load_tail_steps=0), dict(load_tail_steps=-1)])
def test_a_tail_out_of_range_is_refused_naming_it(bad):
    with pytest.raises(ValueError, match="load tail"):
        _tailed(**bad)


def test_the_default_config_reaches_500_mbar_at_0_007_mpa_and_its_geometry_does_not():
    cfg = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    spec = RaySpec.from_config(cfg["scale_free_space"], cfg.get("mesh"),
                               cfg.get("mesh_fallback"))
    assert spec.x1d_lower(500.0) <= 0.007
    assert spec.untailed().x1d_lower(500.0) == pytest.approx(0.025)
    # the rays on demand (a subject's layers) are the geometry spaces' rays
    on_demand = OnDemandRays(spec, cache_dir=None, progress=None, geometry=None)
    assert on_demand.spec == spec.untailed()


@pytest.fixture(scope="module")
def tailed_space(tmp_path_factory):
    spec = _tailed()
    return spec, build_ray_spaces(spec, {}, out_dir=tmp_path_factory.mktemp("tail"),
                                  workers=2, progress=None)["neo_hookean"]


def test_the_tail_is_read_within_the_target_of_direct_fe_runs_off_its_nodes(tailed_space):
    """At a ratio node (no interpolation across rays), to 500 mbar on the softest X1d the
    ray reaches: the read along the tail, cubic on its 8 nodes, against an FE run at
    every 10 mbar."""
    from skinsuction.evaluation import AccuracyPoint, compare_point

    from skinsuction.space import coverage_frontier

    spec, space = tailed_space
    # a neo-Hookean ray stops in the tail (no fallback there): read 500 mbar within its reach
    reach = coverage_frontier(space).set_index("ratio").loc[2.0, "load_reached"]
    assert reach > 30000.0, "the tail carries the stiff-hypodermis ray well beyond 2e4"
    x1d = 500.0 / (0.95 * reach)
    point = AccuracyPoint("neo_hookean", 2.0, x1d, 2.0, float("nan"), 500.0, 10.0)
    rec = compare_point(space, point)
    assert rec["fe_converged"], "the FE run must reach 500 mbar at X1h/X1d = 2"
    p = np.asarray(rec["pressure_mbar"])
    in_tail = p / x1d > 20000.0
    assert in_tail.sum() >= 15 and rec["n_fe_only"] == 0
    fe, read = np.asarray(rec["fe_mm"]), np.asarray(rec["space_mm"])
    rel = np.abs(read - fe) / fe
    assert rel[in_tail].max() < 2e-3, rel[in_tail].max()
    # the tail's nodes are 2.3 to 8 times further apart than the even steps, yet read
    # about as well: within 3 times the even part's worst
    assert rel[in_tail].max() < 3 * max(rel[~in_tail].max(), 2e-4)


def test_a_pair_space_short_of_the_curves_load_gets_no_second_effect_and_says_why():
    """Pair spaces built before the tail stop at 2·10⁴: a ramp that needs more at the
    single cause's X1d is not given a pair from beyond their reach, and the step says so."""
    from types import SimpleNamespace as NS

    from skinsuction.diagnose._pairs import _within_reach

    run = NS(fd={2.0: NS(pressure_mbar=np.linspace(0, 400, 41)),
                 6.0: NS(pressure_mbar=np.linspace(0, 300, 31))})
    untailed, tailed = NS(spec=_tailed().untailed()), NS(spec=_tailed())
    soft, stiff = NS(parameters={"X1d": 0.012}), NS(parameters={"X1d": 0.03})
    # 400 mbar on X1d 0.012: q = 33 300, beyond 20 000, within 71 500
    kept, why = _within_reach(run, [("a", untailed)], soft)
    assert kept == [] and "reach p/X1d <= 20000" in why and "33333" in why
    kept, why = _within_reach(run, [("a", untailed), ("b", tailed)], soft)
    assert [n for n, _ in kept] == ["b"] and why is None
    kept, why = _within_reach(run, [("a", untailed)], stiff)  # q = 13 300
    assert [n for n, _ in kept] == ["a"] and why is None


def test_pairs_built_before_the_tail_are_found_for_tailed_singles(tmp_path):
    from skinsuction.space import SHIPPED_SPACE_DIR, pairs_for, read_pair_spaces

    shipped = read_pair_spaces(SHIPPED_SPACE_DIR)
    assert shipped, "the package ships the pair spaces"
    spec = next(iter(shipped.values())).spec
    base = spec.untailed()
    tailed = RaySpec(**{**base.to_dict(), "load_max": 71500.0,
                        "load_tail_from": base.load_max, "load_tail_steps": 16})
    assert set(pairs_for(tmp_path, tailed)) == set(shipped)
    # another even part is other rays: not served
    other = RaySpec(**{**tailed.to_dict(), "load_steps": base.load_steps + 1})
    assert pairs_for(tmp_path, other) == {}
