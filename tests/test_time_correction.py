"""The FE correction of time fits: the fast path's error measured at the fit and removed."""

from __future__ import annotations

import numpy as np
import pytest

from skinsuction.evaluation import mode1_suction, virtual_skin_curve, write_time_csv
from skinsuction.identify import fe_corrected_fit, fit_time_model
from skinsuction.identify.time_curves import prepare_time_fit
from skinsuction.measured import load_time_curves
from skinsuction.model import Skin
from skinsuction.viscoelastic import Prony

STIFF = "strain_stiffening"
#: A skin the fast path misses by tens of µm under the 8 mm probe: strong creep at large
#: strain on a stiffening dermis (a draw of the effects benchmark, docs/effects.md).
TRUTH = {"X1d": 0.046, "X1h": 0.00115, "X2d": 0.367, "g": 0.73, "tau_s": 0.76}


def _skin(p):
    return Skin.two_layer(p["X1d"], p["X1h"], x2d=p["X2d"],
                          spectrum=Prony(list(np.atleast_1d(p["g"])),
                                         list(np.atleast_1d(p["tau_s"]))))


@pytest.fixture(scope="module")
def fe_curves(tmp_path_factory):
    """The FE time solves of TRUTH on the space's mesh (the correction's), noise-free,
    under the 2 and 8 mm probes (one probe leaves X1d and X2d in a valley): the truth
    is then a fixed point of the correction."""
    suction = mode1_suction(400.0, on_s=1.5, off_s=1.5, cycles=1)
    curves = []
    for probe in (2.0, 8.0):
        t, p, _, exact, _ = virtual_skin_curve(_skin(TRUTH), suction, probe_mm=probe,
                                               rate_hz=25.0, noise_mm=0.0, resolution_mm=0.0)
        curves.append((probe, t, p, exact))
    path = write_time_csv(tmp_path_factory.mktemp("fe") / "fe.csv", curves,
                          ["FE, correction mesh"])
    return load_time_curves(path)


def test_the_correction_recovers_the_skin_the_fast_path_misses(fe_curves):
    from skinsuction.space import load_space

    prep = prepare_time_fit(fe_curves, load_space(), noise_um=3.0)
    rays, _ = prep["space"].cause_rays(STIFF, [2.0, 8.0])
    fast = fit_time_model(rays, prep["data"], terms=1, seed=0, repeats=1)
    fit, corrected, rec = fe_corrected_fit(rays, prep["data"], fast, _skin, iterations=3)

    def error(p, key):
        return abs(np.atleast_1d(p[key])[0] / TRUTH[key] - 1)

    # the fast path misses the 8 mm curve by tens of µm, and its fit is not the FE
    # model's: the FE curve of its estimate is far off the data, its spectrum biased
    assert rec["delta_max_um"]["8 mm curve"] > 10.0 > rec["delta_max_um"]["2 mm curve"]
    assert rec["fe_chi2_at_fast_fit"] > 100.0
    assert max(error(fast.parameters, "g"), error(fast.parameters, "tau_s")) > 0.05
    # corrected: the FE model fits, and the spectrum is the truth's within the noise's
    # reach (X2d is the least determined: a tenth)
    assert rec["chi2"][-1] < 0.05 * rec["chi2"][0]
    for key, tol in (("g", 0.03), ("tau_s", 0.03), ("X1d", 0.04), ("X1h", 0.04),
                     ("X2d", 0.12)):
        assert error(fit.parameters, key) < tol, (key, fit.parameters)
    # the corrected data are the measured ones less the fast path's error, and the fitted
    # curve is the FE model's: the residuals agree
    for d, c, fitted, res in zip(prep["data"], corrected, fit.fitted_mm, fit.residual_um):
        np.testing.assert_allclose(d.deflection_mm - fitted, 1e-3 * res, atol=1e-12)
        assert 1e3 * np.abs(d.deflection_mm - c.deflection_mm).max() == pytest.approx(
            rec["delta_max_um"][d.label])


def test_graded_steps_give_the_solve_at_every_sample(fe_curves):
    """The correction's FE solves step 2 ms after each switch, doubling to 0.2 s, and
    read the samples by PCHIP: the same curve as a step at every sample, to a tenth of
    the 3 µm noise; a finer grading comes nearer (the time scheme is second order)."""
    from skinsuction.identify._time_correction import fe_time_curve
    from skinsuction.space import load_space

    prep = prepare_time_fit(fe_curves, load_space(), noise_um=3.0)
    d = next(c for c in prep["data"] if c.probe_mm == 8.0)
    skin = _skin(TRUTH)
    mesh = {"refinement": 0.5}
    samples = fe_time_curve(skin, d, mesh, steps="samples")
    graded = fe_time_curve(skin, d, mesh, steps="graded")
    finer = fe_time_curve(skin, d, mesh, steps="graded", grading=(1e-3, 1.5, 0.1))
    error, finer_error = (1e3 * np.abs(m - samples).max() for m in (graded, finer))
    assert error < 0.3  # µm, against 3 µm noise
    assert finer_error < 0.6 * error
    assert 1e3 * samples.max() > 500  # a large deflection, strong creep: not a trivial case
    with pytest.raises(ValueError, match="graded"):
        fe_time_curve(skin, d, mesh, steps="every")
