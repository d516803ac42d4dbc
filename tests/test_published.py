"""The published Cutometer values: R parameters of FE mode-1 skins (evaluation._published)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from skinsuction.evaluation import PUBLISHED_FACE, box_distance, evaluate_draw
from skinsuction.evaluation._published import draw_parameters, r_values, skin_of
from skinsuction.model import simulate

COARSE = {"refinement": 0.5}
SKIN = {"x1d": 0.018, "ratio": 3e-4 / 0.018, "x2d_over_x1d": 0.0, "g": [0.5, 1.5],
        "tau_s": [0.05, 2.5], "model": "creep", "terms": 2, "seed": None}


def test_box_distance_is_zero_inside_and_the_scaled_excess_outside():
    inside = {k: (lo + hi) / 2 for k, (lo, hi) in PUBLISHED_FACE.items()}
    assert box_distance(inside) == 0.0
    # R7 0.052 above its range of width 0.15, R0 0.013 below its range of width 0.13
    off = {**inside, "R7": 0.572, "R0": 0.187}
    assert box_distance(off) == pytest.approx(0.052 / 0.15 + 0.013 / 0.13)
    assert box_distance({**inside, "R5": math.nan}) == math.inf


def test_an_elastic_skin_reads_no_creep_and_full_recovery():
    # no spectrum: the hold is the quasi-static curve at 450 mbar (an independent solver
    # path, simulate), nothing creeps (R6 = 0) and everything comes back (R2 = R5 = R7 = 1)
    params = {**SKIN, "g": [], "tau_s": []}
    r = r_values(params, mesh=COARSE)
    ramp = simulate(skin_of(params), 2.0, pressures_mbar=np.linspace(0, 450, 46), mesh=COARSE)
    assert r["R0"] == pytest.approx(ramp.deflection_mm[-1], rel=1e-4)
    assert abs(r["R6"]) < 1e-4
    for k in ("R2", "R5", "R7"):
        assert r[k] == pytest.approx(1.0, abs=1e-4), k


def test_stiffening_brings_a_creeping_skin_into_the_published_box():
    # the skin: creep alone unloads along its loading tangent (R5 near 1, R7 too
    # high); the same skin with a stiffening dermis lands inside every published range
    creep = evaluate_draw(SKIN, mesh=COARSE)
    both = evaluate_draw({**SKIN, "x2d_over_x1d": 0.1 / 0.018, "model": "creep+stiffening"},
                         mesh=COARSE)
    assert not creep["inside"] and creep["R7"] > PUBLISHED_FACE["R7"][1]
    assert creep["R5"] > both["R5"] + 0.2
    assert both["inside"], both


def test_draws_are_reproducible_and_inside_the_domain():
    a, b = draw_parameters("creep+stiffening", 7), draw_parameters("creep+stiffening", 7)
    assert a == b and a != draw_parameters("creep+stiffening", 8)
    assert draw_parameters("creep", 7)["x2d_over_x1d"] == 0.0
    assert 10 ** -2.3 <= a["x1d"] <= 0.1 and 0 <= a["x2d_over_x1d"] <= 999
    with pytest.raises(ValueError, match="model"):
        draw_parameters("stiffening", 0)
