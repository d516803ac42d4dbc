"""The steps of a pressure ramp's identification (:func:`.measured_fit.identify_data`).

In their order: check the settings (:func:`check_settings`), take the space at
the subject's layers and the curves the objective fits (:func:`setup_ramp`, a
:class:`RampSetup`), run the window focusing and polish its median
(:func:`run_ramp`, a :class:`RampRuns`), flag an estimate on an edge of the space
(:func:`flag_bounds`), summarise the runs (:func:`spread_of`), put intervals on the
estimate and widen them for a thickness sd (:mod:`._ramp_intervals`), and give the
fitted curves (:func:`fit_records`).
Every step appends what the user should read to the setup's ``warnings``, in
that order.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from skinsuction.errors import InputError

from ._bounds import bound_flags
from ._objectives import ratio_objective, single_objective, weighted_objective
from ._engine import repeated_fit
from ._window_focusing import IdentificationError

__all__ = ["OBJECTIVE_KINDS", "SPREAD_WARNING", "RampSetup", "RampRuns", "check_settings",
           "probes_of", "pick_curve", "make_objective", "setup_ramp", "run_ramp",
           "flag_bounds", "spread_of", "fit_records", "bounds_json", "finite_list"]

#: Objectives of ``skinsuction identify --objective``.
OBJECTIVE_KINDS = ("single", "weighted", "ratio")

#: Interquartile range / median of the repeats above which a warning is given.
SPREAD_WARNING = 0.05


# ------------------------------------------------------------------ read and check
def check_settings(alpha, repeats, seed, noise_um, level):
    """Refuse settings out of their range (:class:`InputError`, one line).

    Parameters
    ----------
    alpha, repeats, seed, noise_um, level
        As in :func:`.measured_fit.identify_measured`.

    Returns
    -------
    None
    """
    if not 0.0 <= float(alpha) <= 1.0:
        raise InputError(f"alpha must lie in [0, 1], got {alpha}")
    if int(repeats) < 1:
        raise InputError(f"repeats must be >= 1, got {repeats}")
    if int(seed) < 0:
        raise InputError(f"seed must be >= 0, got {seed}")
    if noise_um is not None and not (math.isfinite(float(noise_um)) and float(noise_um) > 0):
        raise InputError(f"the noise sd must be a positive number of µm, got {noise_um}")
    if not 0.5 <= float(level) < 1.0:
        raise InputError(f"the confidence level must lie in [0.5, 1), got {level}")


def probes_of(objective: str, probe_mm: float, data_probes=()) -> list:
    """Probes (mm) an objective needs: the single one; for two probes, the file's two
    (e.g. 4 and 8 mm), else the paper's 2 and 6 mm."""
    if objective not in OBJECTIVE_KINDS:
        raise InputError(f"objective must be one of {OBJECTIVE_KINDS}, got {objective!r}")
    if objective == "single":
        return [float(probe_mm)]
    probes = sorted(float(p) for p in data_probes)
    return probes if len(probes) == 2 else [2.0, 6.0]


def pick_curve(data, probe, curve_id, path):
    """The one curve of ``probe`` (the replicate ``curve_id`` if given) in ``data``."""
    curves = data.for_probe(probe)
    if not curves:
        have = ", ".join(f"{p:g}" for p in data.probes)
        raise InputError(f"{path}: no {probe:g} mm curve in the file (probes in the file: {have} mm)")
    if curve_id is not None:
        curves = [c for c in curves if c.curve == str(curve_id)]
        if not curves:
            ids = [c.curve for c in data.for_probe(probe)]
            raise InputError(f"{path}: no {probe:g} mm curve with id {curve_id!r} (ids: {ids})")
    if len(curves) > 1:
        ids = [c.curve for c in curves]
        raise InputError(f"{path}: {len(curves)} curves of the {probe:g} mm probe ({ids}); "
                         "choose one with --curve")
    return curves[0]


def make_objective(objective, spaces, curves, probes, alpha, measured_path):
    """The objective of ``objective`` on the probes' spaces and curves."""
    if objective == "single":
        (p,) = probes
        return single_objective(spaces[p], curves[p])
    small, large = probes
    if objective == "weighted":
        return weighted_objective(spaces[small], curves[small], spaces[large], curves[large],
                                  alpha=alpha)
    try:
        return ratio_objective(spaces[small], curves[small], spaces[large], curves[large])
    except ValueError as err:
        raise InputError(f"{measured_path}: ratio objective: {err}") from None


@dataclass
class RampSetup:
    """A ramp's fit once its inputs are read and checked (:func:`setup_ramp`)."""

    data: Any            # MeasuredData
    geometry: Any        # Geometry: the layers, given or assumed
    space: Any           # LoadedSpace at the geometry
    objective: str
    probe_mm: float
    alpha: float
    probes: list         # the probes fitted (mm)
    spaces: dict         # probe -> its space
    curves: dict         # probe -> the measured curve fitted
    obj: Any             # the objective
    scale_free: bool
    warnings: list       # every step appends to it


def setup_ramp(data, space, *, objective, probe_mm, alpha, curve, geometry) -> RampSetup:
    """Take the space at the layers and the curves and objective of the fit.

    Parameters
    ----------
    data : MeasuredData
        The measured curves.
    space : LoadedSpace
        The space read.
    objective, probe_mm, alpha, curve
        As in :func:`.measured_fit.identify_measured`.
    geometry : Geometry or None
        The layers; None takes the file's header (with its warnings).

    Returns
    -------
    RampSetup
        Its ``warnings`` start with the data's and the geometry's.
    """
    from skinsuction.measured import geometry_of
    from skinsuction.space import fit_reach_mm

    geometry_warnings = []
    if geometry is None:
        geometry, geometry_warnings = geometry_of(data)
    space = space.at(geometry, reads_up_to_mm=fit_reach_mm(data.curves))
    probes = space.check_probes(probes_of(objective, probe_mm, data.probes))
    spaces = {p: space.probe(p) for p in probes}
    for c in data.curves:
        space.probe(c.probe_mm)  # every curve must have a space (the loader checks a file)
    curves = {p: pick_curve(data, p, curve, data.path) for p in probes}
    warnings = list(getattr(data, "warnings", ())) + geometry_warnings
    warnings += [f"geometry: {a}" for a in geometry.assumptions()]
    warnings += [f"geometry: {n}" for n in space.notes(probes)]
    obj = make_objective(objective, spaces, curves, probes, alpha, data.path)
    return RampSetup(data, geometry, space, objective, probe_mm, alpha, probes, spaces, curves,
                     obj, any(s.layout == "scale_free" for s in spaces.values()), warnings)


# ------------------------------------------------------------------ fit
@dataclass
class RampRuns:
    """The window focusing runs and the polished estimate (:func:`run_ramp`)."""

    rep: Any               # RepeatedIdentification
    runs_mpa: np.ndarray   # (repeats, 2): each run's X1d, X1h
    best: int              # the run of least E
    wf_est: np.ndarray     # the runs' median before the polish (MPa)
    theta: np.ndarray      # the polished estimate (the objective's coordinates)
    est: np.ndarray        # the same in MPa
    e_est: float           # E at the estimate


def run_ramp(setup: RampSetup, wf: dict, repeats: int, seed: int) -> RampRuns:
    """``repeats`` window focusing runs, their median polished by bounded least squares.

    Parameters
    ----------
    setup : RampSetup
    wf : dict
        ``n_samples``, ``n_best``, ``tolerance``, ``max_iter``.
    repeats, seed : int
        The runs and their seed.

    Returns
    -------
    RampRuns
    """
    obj = setup.obj
    try:
        # the paper's statistic: the coordinate-wise median of the runs' candidates
        # (MPa on a grid space, logs on the scale-free one); the window focusing stops
        # near, not on, the minimum of a flat valley or of a bound, so a bounded
        # least-squares polish from the median finishes the job (and tells whether the
        # best fit of the space sits on its edge)
        fit = repeated_fit(obj, repeats=int(repeats), seed=int(seed), focus_options=wf,
                           estimate="median", skip_failed=False)
    except IdentificationError as err:
        raise InputError(f"{setup.data.path}: beyond the simulated space: no candidate of "
                         f"{setup.space.info['path'] or 'the space'} has a curve over the "
                         f"measured pressures ({err}); see the coverage frontier "
                         "(results/tables/scale_free_coverage.csv)") from None
    rep = fit.runs
    e_est = float(obj.error(float(obj(fit.x.reshape(1, 2))[0])))
    return RampRuns(rep, obj.to_moduli(rep.estimates), int(np.argmin(rep.E)),
                    obj.to_moduli(fit.start)[0], fit.x, obj.to_moduli(fit.x)[0], e_est)


# ------------------------------------------------------------------ bounds and runs
def flag_bounds(setup: RampSetup, runs: RampRuns) -> list:
    """The ``at_bound`` flags of X1d and X1h (:func:`bound_flags`), a warning for each.

    Parameters
    ----------
    setup : RampSetup
    runs : RampRuns

    Returns
    -------
    list of dict
        One flag per parameter.
    """
    obj = setup.obj
    flags = bound_flags(obj, runs.theta, ["X1d", "X1h"],
                        ["log", "log"] if setup.scale_free else ["relative", "relative"],
                        _bound_keys(setup.spaces, obj, setup.space.info))
    for f, value in zip(flags, runs.est):
        if f["at_bound"]:
            setup.warnings.append(_bound_warning(f, value))
    return flags


def _bound_keys(spaces, obj, space_info):
    """Configuration keys that widen each end of the X1d and X1h axes."""
    first = next(iter(spaces.values()))
    if first.layout == "scale_free":
        spec = first.space.spec
        raised = obj.lower[0] > math.log10(spec.x1d_range[0]) + 1e-12
        x1d_lo = ("scale_free_space.load.max (the curve's largest pressure over load.max "
                  "sets the lowest X1d)" if raised else "scale_free_space.x1d_mpa.min")
        return [(x1d_lo, "scale_free_space.x1d_mpa.max"),
                ("scale_free_space.ratio", "scale_free_space.ratio")]
    name = space_info.get("name") or "<name>"
    return [(f"spaces.{name}.x1d", f"spaces.{name}.x1d"),
            (f"spaces.{name}.x1h", f"spaces.{name}.x1h")]


def _bound_warning(flag, value) -> str:
    where = ("the end of the simulated window" if flag["edge"] == "window"
             else "the coverage frontier (the FE rays or grid points stop there)")
    return (f"AT BOUND: {flag['parameter']} = {value:.4g} MPa sits at the {flag['side']} "
            f"edge of the simulated space ({where}); the best value may lie beyond it. "
            f"Widen it with {flag['config_key']}")


def spread_of(setup: RampSetup, runs: RampRuns, max_iter: int) -> dict:
    """The spread of the runs (the ``spread`` of the JSON), with warnings on the runs.

    Parameters
    ----------
    setup : RampSetup
    runs : RampRuns
    max_iter : int
        The runs' iteration limit (named in the warning of runs that hit it).

    Returns
    -------
    dict
        sd, relative sd and interquartile range, range of X1d and X1h over the runs.
    """
    warnings, rep, runs_mpa = setup.warnings, runs.rep, runs.runs_mpa
    q25, q75 = np.percentile(runs_mpa, [25, 75], axis=0)
    if not math.isfinite(runs.e_est):
        warnings.append("the median estimate falls where the space is not usable "
                        "(non-converged FE points); see best_run")
    if not rep.converged.all():
        warnings.append(f"{int((~rep.converged).sum())} of {len(rep.converged)} runs hit "
                        f"max_iter={max_iter} before the stop criterion")
    mean = runs_mpa.mean(axis=0)
    std = runs_mpa.std(axis=0, ddof=1) if len(runs_mpa) > 1 else np.zeros(2)
    rel_spread = std / np.abs(mean)
    rel_iqr = (q75 - q25) / np.abs(runs.est)
    if rel_iqr.max() > SPREAD_WARNING:
        warnings.append(f"the repeats disagree by more than {100 * SPREAD_WARNING:g} % "
                        f"(interquartile range / median: X1d {100 * rel_iqr[0]:.1f} %, "
                        f"X1h {100 * rel_iqr[1]:.1f} %): the curves do not pin both moduli down")
    return {
        "x1d_std_mpa": float(std[0]), "x1h_std_mpa": float(std[1]),
        "x1d_relative_std": float(rel_spread[0]), "x1h_relative_std": float(rel_spread[1]),
        "x1d_relative_iqr": float(rel_iqr[0]), "x1h_relative_iqr": float(rel_iqr[1]),
        "x1d_iqr_mpa": [float(q25[0]), float(q75[0])],
        "x1h_iqr_mpa": [float(q25[1]), float(q75[1])],
        "x1d_range_mpa": [float(runs_mpa[:, 0].min()), float(runs_mpa[:, 0].max())],
        "x1h_range_mpa": [float(runs_mpa[:, 1].min()), float(runs_mpa[:, 1].max())],
    }


# ------------------------------------------------------------------ the result's parts
def fit_records(setup: RampSetup, theta) -> dict:
    """Per probe: the measured and fitted curves at ``theta`` and the residuals (µm).

    Parameters
    ----------
    setup : RampSetup
    theta : array_like
        The estimate (the objective's coordinates).

    Returns
    -------
    dict
        ``{"6": {"curve", "pressure_mbar", "measured_mm", "fitted_mm", "residual_um"}}``.
    """
    fit = {}
    for p, c in setup.curves.items():
        fitted = single_objective(setup.spaces[p], c).curves(theta.reshape(1, 2))[0]
        fit[f"{p:g}"] = {
            "curve": c.curve,
            "pressure_mbar": c.pressure_mbar.tolist(),
            "measured_mm": c.deflection_mm.tolist(),
            "fitted_mm": finite_list(fitted),
            "residual_um": finite_list(1e3 * (c.deflection_mm - fitted)),
        }
    return fit


def bounds_json(obj, scale_free: bool) -> dict:
    """The search box of the objective in MPa (and X1h/X1d on the scale-free space)."""
    lo, hi = obj.to_moduli(obj.lower)[0], obj.to_moduli(obj.upper)[0]
    if scale_free:  # a box in (X1d, X1h/X1d)
        return {"bounds_mpa": {"x1d": [float(lo[0]), float(hi[0])]},
                "bounds_x1h_over_x1d": [float(10 ** obj.lower[1]), float(10 ** obj.upper[1])]}
    return {"bounds_mpa": {"x1d": [float(lo[0]), float(hi[0])],
                           "x1h": [float(lo[1]), float(hi[1])]}}


def finite_list(a):
    """``a`` as a list of floats, None where it is not finite."""
    return [float(x) if np.isfinite(x) else None for x in np.asarray(a, dtype=float)]
