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
    PairRaySpace,
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
    """M exactly representable: log M cubic in (log r, u1, u2), M proportional to q (so
    log M linear in log q above the first load, M linear in q below it, M(0) = 0)."""
    g = (0.3 * log_r - 0.05 * log_r ** 2 + 0.01 * log_r ** 3 - 0.4 * u1 + 0.07 * u1 ** 2
         - 0.8 * u2 + 0.5 * u2 * u1 + 0.02 * u2 ** 3 + 0.1 * probe)
    s = q / 20000.0
    return np.exp(g) * s


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


# ------------------------------------------------------------ the ramp's second effect
def _toy(x1d, r, c1, c2, p, probe):
    """A smooth family with the scaling law and two effects that do not compose in log M."""
    q = p / (1e4 * x1d)
    soft = 0.4 * (1 + 0.2 / (r + 0.02)) if probe == 6 else 0.1 * (1 + 0.01 / (r + 0.02))
    m = soft * q / (1 + 0.3 * soft * q)
    m = m / (1 + 0.05 * c1 * m ** 2 * (1 + 4 * (c2 - 1)))  # pre-stretch stiffens the X2 term
    return m / (1 + 0.5 * (c2 - 1) / (0.02 + m))


def _toy_spaces():
    spec = RaySpec([2, 6], np.geomspace(0.005, 0.5, 9), load_max=5000, load_steps=20,
                   x1d_range=(0.02, 0.2), x1d_ref=0.02)
    p = np.asarray(spec.pressures_mbar)
    stiff, pre = REG["strain_stiffening"], REG["pre_tension"]

    def rays(n1, n2):
        return {probe: np.array([[_toy(spec.x1d_ref, r, c1, c2, p, probe) for c1 in n1
                                  for c2 in n2] for r in spec.ratio_nodes])
                for probe in spec.probes_mm}

    spaces = {BASELINE: RaySpace(None, spec, np.array([np.nan]), rays([0.0], [1.0])),
              stiff.name: RaySpace(stiff, spec, np.array(stiff.nodes), rays(stiff.nodes, [1.0])),
              pre.name: RaySpace(pre, spec, np.array(pre.nodes), rays([0.0], pre.nodes))}
    pair = CausePair(stiff, pre)
    coords = np.array([(a, b) for a in stiff.nodes for b in pre.nodes])
    pairs = {pair.name: PairRaySpace(stiff, spec, coords, rays(stiff.nodes, pre.nodes), {},
                                     second=pre)}
    return spaces, pairs


def _toy_data(x1d, r, c1, c2, noise_um, seed):
    from skinsuction.measured import MeasuredCurve, MeasuredData

    rng = np.random.default_rng(seed)
    p = np.arange(0.0, 101.0, 2.0)
    curves = []
    for probe in (2.0, 6.0):
        m = _toy(x1d, r, c1, c2, p, probe) + rng.normal(0, 1e-3 * noise_um, p.size)
        m[0] = 0.0
        curves.append(MeasuredCurve(probe, p, m, "", 1))
    return MeasuredData("toy.csv", tuple(curves), {}, ())


FAST = dict(repeats=1, window_focusing={"n_samples": 400, "n_best": 10, "tolerance": 1e-6,
                                        "max_iter": 100})


@pytest.mark.parametrize("c1, c2, effects", [
    (16.0, 1.08, ["strain_stiffening", "pre_tension"]),
    (16.0, 1.0, ["strain_stiffening"]),
    (0.0, 1.0, []),
])
def test_the_second_effect_is_added_only_where_it_earns_its_place(c1, c2, effects, tmp_path):
    from skinsuction.diagnose import Settings, diagnose, write_report

    spaces, pairs = _toy_spaces()
    data = _toy_data(0.03, 0.02, c1, c2, 1.0, 4)
    report = diagnose(data, spaces, Settings(**FAST), pairs=pairs,
                      source={"file": "toy.csv", "sha256": "0"})
    assert sorted(report["effects"]) == sorted(effects), report["summary"]
    step = report["second_effect"]
    assert step["tried"] == bool(effects), step["why"]
    if len(effects) == 2:
        assert report["verdict"] == "cause_found" and report["cause"] == report["effects"][0]
        added = step["added"]
        # both effects earn their place: against each cause alone
        assert added["delta_bic"] <= -10 and added["delta_bic_vs_added_alone"] <= -10
        ci = added["intervals"]
        for name, truth in (("X1d", 0.03), ("X2d", 16.0 * 0.03), ("lambda0", 1.08)):
            assert ci[name]["lower"] <= truth <= ci[name]["upper"], (name, ci[name])
        assert report["extended"]["parameters"]["X2d"] == pytest.approx(0.48, rel=0.1)
        assert [s["added"] for s in report["steps"]] == report["effects"]
        assert "Two effects" in report["summary"]
        paths = write_report(report, tmp_path)
        md = paths["md"].read_text()
        assert "## Second effect" in md and "**added**" in md
        # a study's row carries both effects' parameters from the pair's fit
        from skinsuction.cohort._rows import RESULT_COLUMNS, _diagnosis_columns

        row = _diagnosis_columns(report)
        assert set(row) <= set(RESULT_COLUMNS) and row["effects"] == ",".join(effects)
        second = {"X2d": "lambda0", "lambda0": "X2d"}[row["extra_parameter"]]
        assert row["extra2_parameter"] == second
        assert row["extra2_value"] == added["parameters"][second]
        assert row["extra2_lower"] <= row["extra2_value"] <= row["extra2_upper"]
    elif effects:
        # the pair was fitted but did not beat the stiffening alone
        assert step["added"] is None and step["options"]
        assert step["options"][0]["delta_bic"] > -10
        assert "does not earn its place" in report["summary"]


def test_no_second_effect_at_the_subjects_layers():
    from skinsuction.diagnose import Settings
    from skinsuction.diagnose._pairs import second_effect

    class Run:  # the only attributes the step reads before it fits
        geometry = type("G", (), {"is_default": False})()
        settings = Settings()

    step = second_effect(Run(), [{"cause": "strain_stiffening", "decisive": True, "bic": 0}],
                         {}, {"p": object()})
    assert not step["tried"] and "subject's layers" in step["why"]
    assert not second_effect(Run(), [], {}, {})["tried"]


# ------------------------------------------------------------- the shipped pair spaces
def test_shipped_pairs_agree_with_their_provenance_and_the_single_spaces():
    import fnmatch
    import tomllib
    from pathlib import Path

    from skinsuction.space import (SHIPPED_SPACE_DIR, pairs_for, read_ray_spaces,
                                   verify_shipped_files)

    assert verify_shipped_files() == []
    singles = read_ray_spaces(SHIPPED_SPACE_DIR)
    pairs = pairs_for(None, singles[BASELINE].spec)
    assert set(pairs) == {"strain_stiffening_and_pre_tension",
                          "strain_stiffening_and_hypodermis_thickness"}
    root = Path(__file__).resolve().parents[1]
    patterns = tomllib.loads((root / "pyproject.toml").read_text())["tool"]["setuptools"][
        "package-data"]["skinsuction"]
    files = sorted((SHIPPED_SPACE_DIR / "pairs").glob("*.parquet"))
    for path in files:
        rel = f"data/scale_free/pairs/{path.name}"
        assert any(fnmatch.fnmatch(rel, p) for p in patterns), rel
        assert path.stat().st_size < 2e6, path  # one file per pair and probe keeps them small
    assert len(files) == 8
    for name, pair in pairs.items():
        assert pair.probes_mm == (2.0, 4.0, 6.0, 8.0), name  # the probes' files read together
        a, b = pair.pair.causes
        j = b.nodes.index(b.neutral)
        # pairs built before the singles' load tail: its loads are the singles' first ones
        n = len(pair.spec.load_nodes)
        assert pair.spec.to_dict() in (singles[a.name].spec.to_dict(),
                                       singles[a.name].spec.untailed().to_dict())
        np.testing.assert_array_equal(pair.spec.load_nodes, singles[a.name].spec.load_nodes[:n])
        for probe in pair.probes_mm:
            # the pair's edges are the single causes' rays (to round-off: the singles were
            # solved again with the tail, the same increments up to its start)
            edge, single = pair.slice_second(j).rays(probe), singles[a.name].rays(probe)[..., :n]
            np.testing.assert_array_equal(np.isfinite(edge), np.isfinite(single))
            np.testing.assert_allclose(edge, single, rtol=1e-10, atol=0)
            assert np.isfinite(pair.rays(probe)).mean() > 0.95


def test_a_random_shipped_pair_ray_is_reproduced_by_the_fe_code():
    from skinsuction.space import SHIPPED_SPACE_DIR, compute_ray, pairs_for, read_ray_spaces

    rng = np.random.default_rng(20261127)
    for pair in pairs_for(None, read_ray_spaces(SHIPPED_SPACE_DIR)[BASELINE].spec).values():
        spec = pair.spec  # the pair's own loads (built before the singles' tail, or with it)
        solver = pair.metadata["rays"]
        # rays the default element carries to the end (a fallback's switch point moves
        # with round-off between machines: the knife-edge rays of the single spaces)
        rays = [r for r in pair_rays(spec, pair.pair) if r["probe_mm"] == 2.0
                and solver[r["ray_id"]]["mesh_fallback"] == 0
                and solver[r["ray_id"]]["converged"]]
        ray = rays[rng.integers(len(rays))]
        curve, _, _ = compute_ray(ray["ray_id"], spec.pressures_mbar, spec.mesh,
                                  list(spec.fallback), spec.fallback_below_mbar)
        a, b = pair.pair.causes
        j = a.nodes.index(ray["coordinate"]) * len(b.nodes) + b.nodes.index(ray["coordinate2"])
        kept = pair.rays(2.0)[spec.ratio_nodes.index(ray["ratio"]), j]
        fresh = np.asarray(curve.deflection_mm, dtype=float)
        ok = np.isfinite(kept)
        assert np.array_equal(np.isfinite(fresh), ok), ray["ray_id"]
        np.testing.assert_allclose(fresh[ok], kept[ok], rtol=1e-6, err_msg=ray["ray_id"])


def test_ramp_effects_summary_counts_a_hand_made_table():
    from skinsuction.evaluation import ramp_effects_summary

    d = "ramp, 4 + 8 mm"
    rows = [
        # a pair, both detectable, both named
        dict(truth="strain_stiffening+hypodermis_thickness", named="strain_stiffening,"
             "hypodermis_thickness", detectable_strain_stiffening=True,
             detectable_hypodermis_thickness=True, fit_x2d=0.33, x2d_mpa=0.3, fit_t_h=2.2,
             t_h_mm=2.0),
        # a pair, both detectable, one named: counts against the pairs
        dict(truth="strain_stiffening+hypodermis_thickness", named="strain_stiffening",
             detectable_strain_stiffening=True, detectable_hypodermis_thickness=True),
        # a single effect named wrong but tied with the truth: not a wrong effect
        dict(truth="pre_tension", named="dermis_thickness", ambiguous_with="pre_tension",
             detectable_pre_tension=True),
        # a wrong effect, not tied
        dict(truth="pre_tension", named="hypodermis_thickness", detectable_pre_tension=False),
        # neo-Hookean skins: one false effect
        dict(truth="none", named=""), dict(truth="none", named="strain_stiffening"),
    ]
    base = dict(design=d, error=None, ambiguous_with="", x1d=0.05, fit_x1d=0.05,
                diagnosis_cpu_s=5.0, fit_x2d=None, x2d_mpa=0.0, fit_lambda0=None, lambda0=1.0,
                fit_t_h=None, t_h_mm=1.0)
    s = ramp_effects_summary(pd.DataFrame([{**base, **r} for r in rows]))[d]
    e = s["effects"]
    assert (e["strain_stiffening"]["detectable"], e["strain_stiffening"]["named"]) == (2, 2)
    assert (e["hypodermis_thickness"]["detectable"], e["hypodermis_thickness"]["named"]) == (2, 1)
    assert e["pre_tension"] == {"with_effect": 2, "detectable": 1, "named": 0,
                                "right_or_tied": 1, "ceiling": None}
    assert s["pairs"] == [1, 2] and s["false_effect"] == [1, 2]
    assert s["wrong_not_tied"] == [1, 4]
    assert s["median_error_pct"]["X2d"][0] == pytest.approx(10.0)
    assert s["median_error_pct"]["t_h"][0] == pytest.approx(10.0)
