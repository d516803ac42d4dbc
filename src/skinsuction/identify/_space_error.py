"""The accuracy of the simulated space, in the likelihood of a ramp's fit.

A point's sd is the noise and the space's accuracy in quadrature
(:data:`MODEL_ERROR_RELATIVE`, :data:`MODEL_ERROR_MM`; :func:`point_sd`); on the
scale-free space its systematic error along a curve enters each probe as one
correlated term (:data:`SPACE_ERROR_RMS` per load, :func:`space_error_direction`,
:func:`decorrelate`).  :func:`likelihood_residuals` gives the whitened residuals of
the measured points that the intervals of :func:`.measured_fit.identify_data` and
the fits of :mod:`skinsuction.diagnose` build on.
"""

from __future__ import annotations

import math

import numpy as np

from skinsuction.space import load

__all__ = ["MODEL_ERROR_RELATIVE", "MODEL_ERROR_MM", "SPACE_ERROR_LOADS", "SPACE_ERROR_RMS",
           "DISCRETISATION_ERROR_HEIGHTS", "DISCRETISATION_ERROR_RMS", "point_sd",
           "space_error_rms", "discretisation_error_rms", "correlated_error_rms",
           "space_error_direction", "decorrelate", "likelihood_residuals"]

#: Accuracy of the scale-free space, the target it was built to (0.2 % of M or
#: 0.3 µm; measured against direct FE runs: 0.17 % at the 95th percentile, more for
#: soft skin under the 6 mm probe), added in quadrature to the noise of each point in
#: the intervals: without it the 6 mm intervals covered 88 % on FE curves.
MODEL_ERROR_RELATIVE = 2e-3
MODEL_ERROR_MM = 0.3e-3

#: The error of the scale-free space against direct FE runs is systematic: smooth
#: along a curve, and growing with the load q = p / X1d under the 6 mm probe (large
#: domes of soft skin).  Its relative rms per load (mbar/MPa), per probe, measured by
#: ``python benchmarks/space_error_profile.py`` on FE virtual experiments that are not
#: those of the coverage benchmark (seeds 7000-7119), enters the likelihood of each
#: probe as one correlated term (a rank-one covariance along the curve).
SPACE_ERROR_LOADS = (0.0, 500.0, 1500.0, 3000.0, 5500.0, 8500.0, 12000.0, 17000.0, 20000.0,
                     30000.0, 55000.0, 71500.0)
#: The 4 and 8 mm profiles were measured on the four-probe space (25 November 2026);
#: another aperture takes them linearly in log of the aperture (:func:`space_error_rms`).
#: The load tail (30 000 and 55 000, the centres of its bands 2·10⁴-4·10⁴ and
#: 4·10⁴-71 500): the larger of the last even load's rms and the tail's own, measured by
#: ``python benchmarks/scale_free_accuracy.py --x1d-range 0.007 0.03 --protocol 500 10
#: --points 60 --seed 35`` (27 November 2026: 2 mm 0.0002 / 0.0003, 4 mm 0.0009 / 0.0013,
#: 6 mm 0.0006 / 0.0012, 8 mm 0.0008 / 0.0004).
SPACE_ERROR_RMS = {
    8.0: (0.00046, 0.00046, 0.00081, 0.0014, 0.0024, 0.0026, 0.0037, 0.0064, 0.0064,
          0.0064, 0.0064, 0.0064),
    6.0: (0.0003, 0.0003, 0.00033, 0.00049, 0.001, 0.0012, 0.0016, 0.002, 0.002,
          0.002, 0.002, 0.002),
    4.0: (0.00019, 0.00019, 0.00023, 0.00026, 0.00035, 0.0004, 0.00056, 0.0008, 0.0008,
          0.0009, 0.0013, 0.0013),
    2.0: (3.4e-05, 3.4e-05, 3.4e-05, 3e-05, 3.2e-05, 4.5e-05, 3.4e-05, 3.7e-05, 3.7e-05,
          0.0002, 0.0003, 0.0003),
}

#: The FE discretisation of the space itself.  Its mesh (``quad8`` cells, reduced
#: quadrature) is not the mesh limit: against the same skins on a mesh with every
#: element split in four (within 0.06 % of the limit on small domes), measured by
#: ``python benchmarks/discretisation_error.py`` on the confusion benchmark's draws, M
#: differs by a relative rms that grows with the dome's height M over the aperture's
#: radius a (a soft, thin hypodermis under a high dome is too soft on the coarse mesh).
#: It is smooth along a curve, so it joins the space's error in the correlated term,
#: in quadrature (:func:`correlated_error_rms`; ``docs/other_solvers.md``).  Measured
#: on 28 November 2026 over 60 draws (12 per cause, seeds 1000 + 100000 k + i): the rms
#: per probe in bins of M/a (0-0.1, 0.1-0.2, 0.2-0.3, 0.3-0.4, 0.4-0.5, 0.5-0.7,
#: 0.7-1, above 1; 6-30 draws a bin), at the bins' centres, made non-decreasing with
#: the height; the 2 mm probe's last value is carried beyond M/a = 0.7, where no draw went.
DISCRETISATION_ERROR_HEIGHTS = (0.05, 0.15, 0.25, 0.35, 0.45, 0.6, 0.85, 1.2)
DISCRETISATION_ERROR_RMS = {
    2.0: (0.00156, 0.00156, 0.00156, 0.00156, 0.00274, 0.00274, 0.00274, 0.00274),
    4.0: (0.0015, 0.00159, 0.00239, 0.00286, 0.00286, 0.00286, 0.0044, 0.0299),
    6.0: (0.00121, 0.00144, 0.00315, 0.00638, 0.0102, 0.0191, 0.0304, 0.0849),
    8.0: (0.001, 0.00104, 0.00222, 0.00259, 0.00413, 0.00944, 0.0322, 0.0988),
}

#: Switch of the discretisation term (a benchmark compares with and without it).
DISCRETISATION_ERROR = True


def discretisation_error_rms(probe_mm, measured_mm):
    """The relative rms of the space's discretisation error at each deflection.

    Parameters
    ----------
    probe_mm : float
        The aperture (mm): its radius scales the dome's height.
    measured_mm : array_like
        The deflections (mm).

    Returns
    -------
    numpy.ndarray
        :data:`DISCRETISATION_ERROR_RMS` at M / a, linear between the heights of
        :data:`DISCRETISATION_ERROR_HEIGHTS` (the end values beyond them) and, between
        the probes of the table, in log of the aperture (the nearest beyond them);
        zeros when :data:`DISCRETISATION_ERROR` is off.

    Examples
    --------
    >>> r = discretisation_error_rms(6.0, [0.03, 3.0])
    >>> bool(r[0] < 0.005 < r[1])
    True
    """
    m = np.abs(np.asarray(measured_mm, dtype=float))
    if not DISCRETISATION_ERROR:
        return np.zeros_like(m)
    return np.interp(m / (0.5 * float(probe_mm)), DISCRETISATION_ERROR_HEIGHTS,
                     _per_aperture(DISCRETISATION_ERROR_RMS, probe_mm))


def correlated_error_rms(probe_mm, pressure_mbar, measured_mm, x1d_mpa):
    """The relative rms of the correlated term at each point: the space's error at
    the point's load p / X1d (:func:`space_error_rms`) and the discretisation's at its
    dome height (:func:`discretisation_error_rms`), in quadrature.

    Parameters
    ----------
    probe_mm : float
        The aperture (mm).
    pressure_mbar, measured_mm : array_like
        The points' suctions (mbar) and deflections (mm).
    x1d_mpa : float
        The X1d (MPa) at which the load of a point is read.

    Returns
    -------
    numpy.ndarray
        One relative rms per point.
    """
    rms = space_error_rms(probe_mm)
    space = (0.0 if rms is None else
             np.interp(load(pressure_mbar, float(x1d_mpa)), SPACE_ERROR_LOADS, rms))
    return np.hypot(space, discretisation_error_rms(probe_mm, measured_mm))


def point_sd(sigma_mm, measured_mm, model_error, probe_mm=None):
    """The sd of each measured point: the noise and the space's accuracy in quadrature.

    Parameters
    ----------
    sigma_mm : float
        Noise sd of one deflection (mm).
    measured_mm : array_like
        The measured deflections (mm).
    model_error : float
        The space's relative accuracy (:data:`MODEL_ERROR_RELATIVE`); 0 leaves the
        noise alone (no :data:`MODEL_ERROR_MM` floor either).
    probe_mm : float, optional
        The probe: its discretisation error (:func:`discretisation_error_rms`) joins
        the relative accuracy in quadrature.  The discretisation's error is not only a
        smooth offset (the correlated term) but wiggles where the dome meets the probe
        wall at another pressure on another mesh (±0.3 % within 0.05 of M/a), so each
        point carries it too.

    Returns
    -------
    numpy.ndarray
        ``sqrt(sigma^2 + (model_error M)^2 + floor^2)`` per point (mm).
    """
    if not model_error:
        return np.sqrt(sigma_mm ** 2 + np.zeros(np.shape(measured_mm)))
    m = np.abs(np.asarray(measured_mm, dtype=float))
    rel = (model_error if probe_mm is None
           else np.hypot(model_error, discretisation_error_rms(probe_mm, m)))
    return np.sqrt(sigma_mm ** 2 + (rel * m) ** 2 + MODEL_ERROR_MM ** 2)


def _per_aperture(table: dict, probe_mm) -> np.ndarray:
    """A profile of ``table`` ({aperture: values}) at ``probe_mm``: linear in log of the
    aperture between its probes, the nearest one beyond them."""
    table = {float(k): np.asarray(v, dtype=float) for k, v in table.items()}
    p = float(probe_mm)
    if p in table:
        return table[p]
    probes = np.array(sorted(table))
    x = np.clip(math.log(p), math.log(probes[0]), math.log(probes[-1]))
    i = int(np.clip(np.searchsorted(np.log(probes), x) - 1, 0, probes.size - 2))
    lo, hi = probes[i], probes[min(i + 1, probes.size - 1)]
    w = 0.0 if hi == lo else (x - math.log(lo)) / (math.log(hi) - math.log(lo))
    return (1 - w) * table[lo] + w * table[hi]


def space_error_rms(probe_mm):
    """The relative rms of the space's error per load (:data:`SPACE_ERROR_LOADS`) of a
    probe: measured at the probes of :data:`SPACE_ERROR_RMS`, linear in log of the
    aperture between them, the nearest one beyond (None without a table).

    Parameters
    ----------
    probe_mm : float
        The probe's aperture (mm).

    Returns
    -------
    tuple of float or None
        One relative rms per load of :data:`SPACE_ERROR_LOADS`.

    Examples
    --------
    >>> space_error_rms(6.0) == SPACE_ERROR_RMS[6.0]
    True
    >>> bool(np.all(np.asarray(space_error_rms(5.0)) > 0))
    True
    """
    if not SPACE_ERROR_RMS:
        return None
    if float(probe_mm) in SPACE_ERROR_RMS:
        return SPACE_ERROR_RMS[float(probe_mm)]
    return tuple(float(v) for v in _per_aperture(SPACE_ERROR_RMS, probe_mm))


def space_error_direction(probe_mm, pressure_mbar, measured_mm, x1d_mpa, sd):
    """(unit direction, gamma) of the correlated space error of one probe's points.

    The covariance of the points is ``diag(sd^2) + v v^T`` with ``v`` the rms
    error of the space and of its discretisation at each point
    (:func:`correlated_error_rms`); whitened residuals ``z = r / sd`` become
    ``z - gamma (z . a) a`` with ``a = (v / sd) / |v / sd|`` and
    ``gamma = 1 - 1 / sqrt(1 + |v / sd|^2)``, whose squared norm is the chi2 of
    that covariance (Sherman-Morrison).

    Parameters
    ----------
    probe_mm : float
        The probe (its rms profiles, :func:`correlated_error_rms`).
    pressure_mbar, measured_mm : array_like
        The points' suctions (mbar) and measured deflections (mm).
    x1d_mpa : float
        The fit's X1d (MPa): the load of a point is ``p / X1d``.
    sd : array_like
        The points' sd (mm; :func:`point_sd`).

    Returns
    -------
    direction : numpy.ndarray or None
        The unit vector ``a`` (None when there is no correlated error).
    gamma : float
        The shrink factor of the residuals' component along ``a``.
    """
    v = (correlated_error_rms(probe_mm, pressure_mbar, measured_mm, x1d_mpa)
         * np.abs(measured_mm) / sd)
    norm = float(np.sqrt(v @ v))
    if norm == 0.0:
        return None, 0.0
    return v / norm, 1.0 - 1.0 / math.sqrt(1.0 + norm ** 2)


def decorrelate(z, direction, gamma):
    """Whitened residuals ``z`` (N, n) under the correlated space error of
    :func:`space_error_direction`: ``z - gamma (z . a) a``, row by row.

    Parameters
    ----------
    z : numpy.ndarray
        Residuals / sd, one row per candidate (N, n).
    direction : numpy.ndarray or None
        The unit vector ``a`` (n,); None returns ``z`` itself.
    gamma : float
        The shrink factor of :func:`space_error_direction`.

    Returns
    -------
    numpy.ndarray
        The decorrelated residuals (N, n): their squared norm is the chi2.
    """
    if direction is None:
        return z
    # einsum, not @: a matrix-vector product of many rows would start BLAS threads
    return z - gamma * np.einsum("nt,t->n", z, direction)[:, None] * direction[None, :]


def likelihood_residuals(obj, objective, curves, sigma_mm, model_error=MODEL_ERROR_RELATIVE,
                         x1d_mpa=None):
    """Residuals / sd of each point of the curves the objective fits, vectorised.

    The sd of a point is the noise and the accuracy of the space (relative to
    M) in quadrature; on the scale-free space (``x1d_mpa`` given, the fit's X1d)
    the space's systematic error enters each probe's curve as one correlated
    term (:data:`SPACE_ERROR_RMS`).  The likelihood is that of the measured
    points, whatever the objective: the weighted objective's alpha changes the
    estimate, not the likelihood.  The ratio's sd follows from the two
    deflections' (first-order propagation).

    Parameters
    ----------
    obj : SingleObjective, WeightedObjective or RatioObjective
        The objective of the fit.
    objective : {"single", "weighted", "ratio"}
        Its kind.
    curves : dict
        The measured curves it fits, per probe (unused; the objective holds them).
    sigma_mm : float
        Noise sd of one deflection (mm).
    model_error : float
        The space's relative accuracy (0 on a grid database).
    x1d_mpa : float, optional
        The fit's X1d (MPa), for the correlated space error; None leaves it out.

    Returns
    -------
    callable
        ``theta (N, 2) -> residuals / sd (N, n)``.
    """
    def block(o):
        # each curve's own probe: a weighted fit of 4 + 8 mm curves holds them in its
        # objective_2mm / objective_6mm slots (the small and the large probe)
        sd = point_sd(sigma_mm, o.measured_mm, model_error, o.space.probe_mm)
        a, g = ((None, 0.0) if x1d_mpa is None else
                space_error_direction(o.space.probe_mm, o.pressure_mbar, o.measured_mm,
                                      x1d_mpa, sd))
        return sd, a, g

    if objective == "single":
        sd, a, g = block(obj)
        return lambda t: decorrelate(obj.residuals(t) / sd, a, g)
    if objective == "weighted":
        b2, b6 = block(obj.objective_2mm), block(obj.objective_6mm)
        return lambda t: np.concatenate(
            [decorrelate(obj.objective_2mm.residuals(t) / b2[0], b2[1], b2[2]),
             decorrelate(obj.objective_6mm.residuals(t) / b6[0], b6[1], b6[2])], axis=1)
    m2 = np.abs(obj.objective_2mm.measured_mm)
    m6 = np.abs(obj.objective_6mm.measured_mm)
    s2 = point_sd(sigma_mm, m2, model_error, obj.objective_2mm.space.probe_mm)
    s6 = point_sd(sigma_mm, m6, model_error, obj.objective_6mm.space.probe_mm)
    with np.errstate(divide="ignore"):
        sd = np.abs(obj.gamma) * np.sqrt((s2 / m2) ** 2 + (s6 / np.maximum(m6, 1e-12)) ** 2)
    return lambda t: obj.residuals(t) / sd


