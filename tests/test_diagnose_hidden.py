"""Hidden-effect tests: FE-made virtual experiments, diagnosed as a user would.

Once per session the coarse scale-free space of config/ci.yaml is built
(refinement 0.5, 5 ratios X1h/X1d, 4 values per cause: 100 FE rays).  Each test draws from
a seed which moduli, which effect size and which noise a virtual experiment
has, runs the FE model directly at those parameters (on the same mesh as the
spaces, so the test sees the interpolation and the statistics, not the mesh),
writes the curves as a measured CSV and runs ``skinsuction diagnose`` on it
through :func:`skinsuction.commands.diagnose.run`.  It requires the hidden cause,
a decisive gain, and the extended parameters within tolerance; and ``none``
for a neo-Hookean experiment.

Ranges of the draws, and why (see benchmarks/diagnose_confusion.py for the
rates over many draws):

* the effects change the shape of M(p) only where the skin deforms a lot: a
  soft dermis and a much softer hypodermis.  At X1d = 0.04 MPa and
  X1h / X1d = 0.03 the neo-Hookean model absorbs X2d / X1d = 4, t_d = 1.6 mm or
  lambda0 = 1.06 in its two moduli to better than 0.5 µm RMS, below any noise
  of a Cutometer; at X1d <= 0.035 MPa and X1h / X1d <= 0.02 (6 mm deflection
  at 100 mbar 0.6-1.2 mm) they leave 1-20 µm.  So X1d is drawn in
  0.025-0.035 MPa, X1h / X1d in 0.006-0.02 (log-uniform);
* effect sizes from where the misfit they leave exceeds about half the noise:
  X2d / X1d in 6-14, t_d in 1.6-2.0 mm, lambda0 in 1.05-1.11;
* the noise sd in 1-2.5 µm (a Cutometer resolves about 1-10 µm; larger
  noise needs larger effects).
"""

import argparse
import json
import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from skinsuction.commands.diagnose import add_arguments
from skinsuction.commands.diagnose import run as command
from skinsuction.diagnose import NONE, registry_from_config
from skinsuction.evaluation import DETECTABLE_EFFECTS, DRAW_RANGES, draw_experiment, write_csv
from skinsuction.space import RaySpec, build_ray_spaces

ROOT = Path(__file__).resolve().parents[1]

#: Effect-size ranges and moduli/noise ranges of the draws (shared with the benchmark).
EFFECTS = DETECTABLE_EFFECTS
RANGES = DRAW_RANGES
#: A thicker dermis and a pre-tension change both curves almost alike; their BICs tie
#: mostly where the hypodermis is less soft (X1h / X1d above 0.01; see the confusion
#: benchmark).  The pre-tension test draws X1h / X1d in 0.006-0.01, and
#: test_thick_dermis_and_pre_tension_tie_is_reported covers the tie.
RANGES_BY_CAUSE = {"pre_tension": {**RANGES, "x1h_over_x1d": (0.006, 0.01)}}
#: Tolerances on the extended parameters (relative for moduli, absolute otherwise).
TOLERANCE = {"X1d": 0.15, "X2d": 0.35, "t_d": 0.25, "lambda0": 0.02}


@pytest.fixture(scope="session")
def ci_spaces(tmp_path_factory):
    cfg = yaml.safe_load((ROOT / "config" / "ci.yaml").read_text())
    d = cfg["scale_free_space"]
    spec = RaySpec.from_config(d, cfg.get("mesh"), cfg.get("mesh_fallback"))
    causes = registry_from_config(d["causes"])
    out = tmp_path_factory.mktemp("ci_spaces")
    build_ray_spaces(spec, causes, out_dir=out, workers=2, config=cfg)
    return out, spec, causes, d


def run_user(csv, space_dir, out, *extra):
    parser = argparse.ArgumentParser()
    add_arguments(parser)
    args = parser.parse_args([str(csv), "--out", str(out), "--space-dir", str(space_dir),
                              "--repeats", "1", *extra])
    assert command(args) == 0
    return json.loads((Path(out) / "report.json").read_text())


@pytest.mark.parametrize("cause,seed", [(NONE, 11), ("strain_stiffening", 12),
                                        ("dermis_thickness", 13), ("pre_tension", 14)])
def test_hidden_effect_is_named(ci_spaces, tmp_path, cause, seed):
    space_dir, spec, causes, _ = ci_spaces
    c = causes.get(cause)
    ve = draw_experiment(seed, c, effect_range=EFFECTS.get(cause),
                         ranges=RANGES_BY_CAUSE.get(cause, RANGES), mesh=spec.mesh)
    assert ve.converged
    csv = write_csv(ve, tmp_path / "virtual.csv", ["hidden-effect test"])
    report = run_user(csv, space_dir, tmp_path / "out")
    truth = ve.truth
    assert report["cause"] == cause, (truth, report["summary"])
    assert report["noise_um"] == pytest.approx(ve.noise_um, rel=0.35)
    if cause == NONE:
        assert not report["baseline"]["systematic_misfit"], report["baseline"]["description"]
        assert report["extended"] is None and report["gain"] is None
        base = report["baseline"]["parameters"]
        assert base["X1d"] == pytest.approx(ve.x1d, rel=0.05)
        return
    assert report["baseline"]["systematic_misfit"]
    gain = report["gain"]
    assert gain["delta_bic"] <= -10 and gain["E_ratio"] < 0.9
    ext = report["extended"]["parameters"]
    assert ext["X1d"] == pytest.approx(ve.x1d, rel=TOLERANCE["X1d"])
    sym = c.symbol
    tol = TOLERANCE[sym]
    if c.modulus:
        assert ext[sym] == pytest.approx(ve.value, rel=tol), (sym, ext, truth)
    else:
        assert ext[sym] == pytest.approx(ve.value, abs=tol), (sym, ext, truth)
    # the report says in words where the misfit was
    assert "mm probe" in report["baseline"]["description"]
    for name in ("fit.png", "residuals.png", "gain.png", "report.md"):
        assert (tmp_path / "out" / name).stat().st_size > 0


def test_thick_dermis_and_pre_tension_tie_is_reported(ci_spaces, tmp_path):
    """Pre-tension with a less soft hypodermis: a thicker dermis fits about as well."""
    space_dir, spec, causes, _ = ci_spaces
    ve = draw_experiment(14, causes["pre_tension"], ranges=RANGES, mesh=spec.mesh)
    assert 0.01 < ve.x1h / ve.x1d < 0.02
    report = run_user(write_csv(ve, tmp_path / "v.csv"), space_dir, tmp_path / "out")
    assert report["baseline"]["systematic_misfit"]
    named = report["cause"]
    assert named in ("pre_tension", "dermis_thickness")
    other = ({"pre_tension", "dermis_thickness"} - {named}).pop()
    assert other in report["ambiguous_with"], report["summary"]
    assert "hard to separate" in report["summary"]
    tie = {c["cause"]: c for c in report["candidates"]}
    assert abs(tie["pre_tension"]["bic"] - tie["dermis_thickness"]["bic"]) < 6


def test_replicates_give_the_noise_and_the_same_verdict(ci_spaces, tmp_path):
    space_dir, spec, causes, _ = ci_spaces
    from skinsuction.evaluation import virtual_experiment

    ve = virtual_experiment(0.028, 0.028 * 0.01, None, None, noise_um=3.0, seed=5,
                            mesh=spec.mesh, replicates=3)
    csv = write_csv(ve, tmp_path / "replicates.csv")
    report = run_user(csv, space_dir, tmp_path / "out", "--no-holdout")
    assert report["noise"]["method"] == "replicates"
    assert report["noise_um"] == pytest.approx(3.0, rel=0.15)
    # the mean of 3 curves is fitted: its noise is sd / sqrt(3)
    s = report["noise"]["sigma_fitted_um"]["6"]
    assert s == pytest.approx(math.hypot(report["noise_um"] / math.sqrt(3), 0.3), rel=1e-9)
    assert report["cause"] == NONE


def test_one_probe_file(ci_spaces, tmp_path):
    space_dir, spec, causes, _ = ci_spaces
    c = causes["strain_stiffening"]
    from skinsuction.evaluation import virtual_experiment

    ve = virtual_experiment(0.026, 0.026 * 0.008, c, 12 * 0.026, noise_um=1.5, seed=6,
                            mesh=spec.mesh, probes_mm=(6.0,))
    csv = write_csv(ve, tmp_path / "six.csv")
    report = run_user(csv, space_dir, tmp_path / "out")
    assert report["input"]["probes_mm"] == [6.0]
    assert all(x["holdout_E_um"] is None for x in report["candidates"])
    assert report["baseline"]["systematic_misfit"]
    assert report["cause"] == "strain_stiffening", report["summary"]


#: Accuracy of the coarse ci space (5 ratios, 4 values per cause, 24 load steps) against
#: direct FE runs on its mesh: a relative error of M; the default space's figures
#: (0.17 % at the 95th percentile, 2.1 % at most) are in docs/scale_free_space.md.
CI_ACCURACY = 0.08


def test_scale_free_space_matches_direct_fe_runs(ci_spaces):
    """A handful of random points across the domain: FE on the rays' mesh vs the space."""
    from skinsuction.space import read_ray_spaces
    from skinsuction.evaluation import compare_point, draw_points

    space_dir, spec, causes, _ = ci_spaces
    spaces = read_ray_spaces(space_dir)
    records = [compare_point(spaces[pt.model], pt)
               for pt in draw_points(spaces, 6, seed=7, x1d_range=(0.02, 0.15))]
    compared = [r for r in records if r["n_compared"]]
    assert len(compared) >= 5  # the draws lie inside the coverage of the space
    worst = max(r["max_relative_error"] for r in compared)
    assert worst < CI_ACCURACY, [(r["model"], r["max_relative_error"]) for r in compared]
    # the median error is far smaller than the worst, and not 0 by construction (the
    # points are off the rays)
    median = float(np.median([r["max_relative_error"] for r in compared]))
    assert 1e-6 < median < CI_ACCURACY / 4


#: The physiological domain of the confusion benchmark (skinsuction.evaluation.WIDE_DOMAIN),
#: within the coarse ci space's axes (X2d/X1d to 30, t_d 0.6-2.2 mm).
CI_DOMAIN = {
    "x1d_mpa": (0.008, 0.15),
    "x1h_over_x1d": (0.003, 0.1),
    "noise_um": (1.0, 5.0),
    "protocols": ((100.0, 2.0), (300.0, 5.0)),
    "effects": {"strain_stiffening": ("log", 2.0, 28.0),
                "dermis_thickness": ("uniform", 0.65, 2.1),
                "pre_tension": ("uniform", 1.02, 1.24)},
    "probe_pairs": ((2.0, 6.0),),  # the ci space has the 2 and 6 mm probes
}


#: Draws the diagnosis does not yet get right on the coarse ci space (found by this
#: test, kept as strict expected failures so that a fix shows): a detectable thickness
#: named `none`.  The false alarm on the neo-Hookean draw 32 went with the space's
#: discretisation error in the likelihood (28 November 2026, docs/other_solvers.md).
_WIDE_KNOWN_WRONG = {("dermis_thickness", 31), ("dermis_thickness", 32)}


@pytest.mark.parametrize("cause,seed", [
    pytest.param(c, s, marks=pytest.mark.xfail(
        strict=True, reason="known miss of the diagnosis over the wide domain"))
    if (c, s) in _WIDE_KNOWN_WRONG else (c, s)
    for c in (NONE, "strain_stiffening", "dermis_thickness", "pre_tension") for s in (31, 32)])
def test_wide_domain_effect_is_named_where_detectable(ci_spaces, cause, seed):
    """Draws across the physiological domain: a detectable effect is named (or tied),
    an undetectable one is not mistaken for another cause, and neo-Hookean skin gets
    no false alarm."""
    from skinsuction.diagnose import Settings
    from skinsuction.space import read_ray_spaces
    from skinsuction.evaluation import run_draw

    space_dir, spec, causes, _ = ci_spaces
    spaces = read_ray_spaces(space_dir)
    row = run_draw(cause, seed, spaces, Settings(repeats=1), CI_DOMAIN)
    assert row["named"] != "fe_failed", row
    tied = set(filter(None, str(row.get("ambiguous_with") or "").split(";")))
    if cause == NONE:
        assert row["named"] == NONE and row["verdict"] == "neo_hookean_fits", row
    elif row["detectable"]:
        assert row["named"] == cause or cause in tied, row
    else:
        assert row["named"] in (NONE, cause), row


def test_rivals_of_a_cause_are_fitted_on_its_noise_free_curves(ci_spaces):
    """The confusion benchmark asks, per draw, whether another cause can mimic the
    true one.  The true cause's model holds the neo-Hookean one (its neutral value),
    so on the noise-free curves it fits at least as well; the rival is another cause,
    and the draw is distinguishable exactly when the gap reaches the tie rule's."""
    from skinsuction.diagnose import Settings
    from skinsuction.space import read_ray_spaces
    from skinsuction.evaluation import run_draw

    space_dir, spec, causes, _ = ci_spaces
    spaces = read_ray_spaces(space_dir)
    settings = Settings(repeats=1)
    row = run_draw("pre_tension", 32, spaces, settings, CI_DOMAIN)
    assert row["named"] != "fe_failed", row
    assert row["own_chi2"] <= row["clean_chi2"] * (1 + 1e-6) + 1e-6, row
    assert row["rival"] in set(spaces) - {"neo_hookean", "pre_tension"}, row
    assert row["rival_gap"] == pytest.approx(row["rival_chi2"] - row["own_chi2"])
    assert row["distinguishable"] == (row["rival_gap"] >= settings.ambiguity_bic)
