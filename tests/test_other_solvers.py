"""Virtual experiments from other discretisations, and the discretisation term of the
likelihood that keeps their differences from moving a verdict (docs/other_solvers.md)."""

import math

import numpy as np
import pandas as pd
import pytest

from skinsuction.evaluation import (OTHER_SOLVERS, SolverRefused, interval_coverage,
                                    solver_curves, wrong_untied)
from skinsuction.identify import _space_error
from skinsuction.identify.measured_fit import (DISCRETISATION_ERROR_HEIGHTS,
                                               DISCRETISATION_ERROR_RMS, correlated_error_rms,
                                               decorrelate, discretisation_error_rms,
                                               space_error_direction)
from skinsuction.space import SHIPPED_SPACE_DIR, read_ray_spaces


@pytest.fixture(scope="module")
def spec():
    return read_ray_spaces(SHIPPED_SPACE_DIR)["neo_hookean"].spec


def test_the_refined_mesh_differs_from_the_space_mesh_as_the_term_says(spec):
    # an independent FE solve on a mesh with every element split in four: the space's
    # own mesh must be off by about the tabulated rms, not by far less or far more
    p = np.arange(0.0, 101.0, 4.0)
    params = {"x1d": 0.03, "x1h": 0.001, "bottom": spec.bottom}
    ref = solver_curves("space", params, [2.0], p, spec.mesh, list(spec.fallback))[2.0]
    fine = solver_curves("refined", params, [2.0], p, spec.mesh, list(spec.fallback))[2.0]
    rel = fine[1:] / ref[1:] - 1
    rms = discretisation_error_rms(2.0, ref[1:])
    assert np.all(np.isfinite(rel))
    ratio = float(np.sqrt(np.mean(rel ** 2)) / np.sqrt(np.mean(rms ** 2)))
    assert 0.3 < ratio < 3.0, (rel, rms)


def test_calculix_refuses_a_pre_stretched_skin_by_name(spec):
    with pytest.raises(SolverRefused, match="pre-stretch"):
        solver_curves("calculix", {"x1d": 0.03, "x1h": 0.001, "prestretch": 1.1}, [2.0],
                      [0.0, 50.0], spec.mesh)
    with pytest.raises(ValueError, match="unknown solver 'abaqus'"):
        solver_curves("abaqus", {"x1d": 0.03, "x1h": 0.001}, [2.0], [0.0, 50.0], spec.mesh)
    assert {"space", "refined", "quad9", "calculix"} <= set(OTHER_SOLVERS)


def test_the_discretisation_term_grows_with_the_dome_and_interpolates_between_probes():
    heights = np.array(DISCRETISATION_ERROR_HEIGHTS)
    for probe, rms in DISCRETISATION_ERROR_RMS.items():
        assert np.all(np.diff(rms) >= 0), probe  # never smaller on a higher dome
        got = discretisation_error_rms(probe, heights * probe / 2)
        np.testing.assert_allclose(got, rms, rtol=1e-12)
    m = np.array([0.1, 1.0, 3.0])
    r4, r6, r5 = (discretisation_error_rms(q, m * q / 6) for q in (4.0, 6.0, 5.0))
    assert np.all(np.minimum(r4, r6) <= r5) and np.all(r5 <= np.maximum(r4, r6))
    # beyond the table's apertures, the nearest one
    np.testing.assert_allclose(discretisation_error_rms(10.0, m * 10 / 8),
                               discretisation_error_rms(8.0, m), rtol=1e-12)


def test_the_correlated_term_forgives_a_discretisation_bias_on_a_high_dome(monkeypatch):
    # a 6 mm dome of 2 mm (M/a 0.67): a curve up to 2 % higher than the model's, smooth
    # along the curve as a coarse mesh's error is (not of the term's own shape), costs
    # chi2 over 100 without the discretisation term and a fraction of it with it
    p = np.arange(2.0, 301.0, 6.0)
    m = 2.0 * (p / p[-1]) ** 0.7
    sd = np.full(p.size, 2e-3)
    r = (0.02 * (p / p[-1]) * m)[None, :] / sd

    def chi2():
        a, gamma = space_error_direction(6.0, p, m, 0.02, sd)
        return float((decorrelate(r, a, gamma) ** 2).sum())

    with_term = chi2()
    monkeypatch.setattr(_space_error, "DISCRETISATION_ERROR", False)
    without = chi2()
    assert without > 100 and with_term < 0.3 * without
    assert np.all(discretisation_error_rms(6.0, m) == 0)
    # the space's own term alone is what is left
    np.testing.assert_allclose(correlated_error_rms(6.0, p, m, 0.02),
                               np.interp(p / 0.02, _space_error.SPACE_ERROR_LOADS,
                                         _space_error.SPACE_ERROR_RMS[6.0]), rtol=1e-12)


def test_wrong_untied_and_interval_coverage_count_what_they_say():
    rows = pd.DataFrame({
        "truth": ["pre_tension"] * 4 + ["none"] * 2,
        "named": ["pre_tension", "hypodermis_thickness", "pre_tension", "fe_failed", "none",
                  "none"],
        "ambiguous_with": ["", "", "hypodermis_thickness", "", "", ""],
        "x1d": [0.02] * 6, "x1h": [1e-4] * 6, "value": [1.1] * 4 + [math.nan] * 2,
        "ci_x1d_lo": [0.019, math.nan, 0.021, math.nan, 0.018, 0.0205],
        "ci_x1d_hi": [0.021, math.nan, 0.022, math.nan, 0.022, 0.021],
        "ci_x1h_lo": [9e-5, math.nan, 9e-5, math.nan, 9e-5, 9e-5],
        "ci_x1h_hi": [2e-4, math.nan, 2e-4, math.nan, 2e-4, 2e-4],
        "ci_value_lo": [1.05, math.nan, 1.12, math.nan, math.nan, math.nan],
        "ci_value_hi": [1.15, math.nan, 1.2, math.nan, math.nan, math.nan],
    })
    assert wrong_untied(rows[rows.truth == "pre_tension"], "pre_tension").tolist() == \
        [False, True, False, False]
    cov = interval_coverage(rows).set_index("truth")
    assert cov.loc["pre_tension", "named_right"] == 2
    assert cov.loc["pre_tension", "value_covered"] == 0.5  # [1.12, 1.2] misses 1.1
    assert cov.loc["pre_tension", "x1d_covered"] == 0.5  # [0.021, 0.022] misses 0.02
    assert cov.loc["none", "x1d_covered"] == 0.5 and cov.loc["none", "x1h_covered"] == 1.0
    assert "value_covered" not in cov.columns or math.isnan(cov.loc["none", "value_covered"])
