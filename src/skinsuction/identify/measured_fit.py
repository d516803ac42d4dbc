"""Identify (X1d, X1h) of a measured suction test on a simulated space.

What ``skinsuction identify`` runs: read and check the measured CSV
(:func:`skinsuction.measured.load_measured`), build the objective (single
probe, weighted or ratio) on the simulated space, run the window focusing
``repeats`` times with independent seeds, and report the median estimate, the
spread over the repeats, E (eq. 7), the iterations, the settings and the
SHA-256 of the input files (:func:`identify_measured`: an
:class:`~skinsuction.identify.Identification`; the steps are in
:mod:`._ramp_steps`); write it as ``identification.json`` with a plot of
measured against fitted curves and their residuals (:func:`write_identification`,
the one writer of both kinds of result, defined in :mod:`._identification`).

Every problem of the inputs raises :class:`InputError` or
:class:`skinsuction.measured.MeasuredDataError` (both ``ValueError``) with a
one-line message.

Examples
--------
>>> import tempfile, pathlib
>>> from skinsuction.identify import analytic_surrogate_space
>>> from skinsuction.space import evaluate
>>> s6 = analytic_surrogate_space(6.0)
>>> d = pathlib.Path(tempfile.mkdtemp())
>>> m = evaluate(s6, [[0.03, 0.0005]])[0]
>>> _ = (d / "m.csv").write_text("probe_mm,pressure_mbar,deflection_mm\\n" + "".join(
...     f"6,{p:g},{x:.6f}\\n" for p, x in zip(s6.pressure_mbar, m)))
>>> r = identify_measured(d / "m.csv", spaces={6.0: s6}, repeats=3, seed=0)
>>> round(r.x1d_mpa, 5), round(r.x1h_mpa, 7)
(0.03, 0.0005)
"""

from __future__ import annotations

import dataclasses
import datetime as _dt

import numpy as np

from skinsuction._files import file_sha256
from skinsuction.errors import InputError
from skinsuction.model import Skin
from skinsuction.space import LoadedSpace, fit_reach_mm, load_space

from ._identification import Identification, write_identification
from ._ramp_intervals import noise_and_intervals, thickness_uncertainty
from ._ramp_steps import (
    OBJECTIVE_KINDS,
    SPREAD_WARNING,
    RampRuns,
    RampSetup,
    bounds_json,
    check_settings,
    fit_records,
    flag_bounds,
    probes_of,
    run_ramp,
    setup_ramp,
    spread_of,
)

# the space's error in the likelihood (:mod:`._space_error`), importable from here
# where it was defined first
from ._space_error import (
    DISCRETISATION_ERROR_HEIGHTS,
    DISCRETISATION_ERROR_RMS,
    MODEL_ERROR_MM,
    MODEL_ERROR_RELATIVE,
    SPACE_ERROR_LOADS,
    SPACE_ERROR_RMS,
    correlated_error_rms,
    decorrelate,
    discretisation_error_rms,
    space_error_direction,
    space_error_rms,
)

__all__ = ["InputError", "OBJECTIVE_KINDS", "SPREAD_WARNING", "identify_measured",
           "identify_data", "write_identification", "Identification", "file_sha256",
           "load_space", "LoadedSpace", "MODEL_ERROR_MM", "MODEL_ERROR_RELATIVE",
           "SPACE_ERROR_LOADS", "SPACE_ERROR_RMS", "SPACE_ERROR_CORRELATED",
           "DISCRETISATION_ERROR_HEIGHTS", "DISCRETISATION_ERROR_RMS",
           "space_error_rms", "discretisation_error_rms", "correlated_error_rms",
           "space_error_direction", "decorrelate"]

#: Switch of the correlated term of the space's error in the likelihood
#: (:data:`SPACE_ERROR_RMS`; a benchmark compares with and without).
SPACE_ERROR_CORRELATED = True

#: The window focusing of a ramp: N, Nb, C, max_iter (``--window-focusing`` overrides).
RAMP_WF = {"n_samples": 1000, "n_best": 20, "tolerance": 1e-6, "max_iter": 200}


def identify_measured(
    measured_path,
    space_path=None,
    *,
    objective: str = "single",
    probe_mm: float = 6.0,
    alpha: float = 0.5,
    repeats: int = 100,
    seed: int = 0,
    bottom: str = "fixed",
    curve: str | None = None,
    window_focusing: dict | None = None,
    spaces: dict | None = None,
    noise_um: float | None = None,
    level: float = 0.95,
    thickness: dict | None = None,
    solve_on_demand: bool = True,
    workers: int = 1,
) -> Identification:
    """Identify (X1d, X1h) of the measured curves in ``measured_path``.

    Parameters
    ----------
    measured_path : path-like or MeasuredData
        Measured CSV (format: :mod:`skinsuction.measured`), or its curves already read.
    space_path : path-like, optional
        The scale-free space (its directory or its ``neo_hookean.parquet``), or a grid
        database such as ``results/simulated_space/paper.parquet``.  Default: the
        workflow's ``results/simulated_space/scale_free`` if built here, else the
        shipped one (:func:`skinsuction.space.resolve_space`; the result's ``space``
        says which).
    objective : {"single", "weighted", "ratio"}
        ``single``: the curve of ``probe_mm`` alone (eq. 4); ``weighted``: the 2 and
        6 mm curves, ``alpha`` on 2 mm (eq. 10); ``ratio``: 6 mm / 2 mm (eqs. 11-12).
    probe_mm : float
        Probe of the single objective (mm).
    alpha : float in [0, 1]
        Weight of the 2 mm curve in the weighted objective.
    repeats : int
        Independent window focusing runs (paper: 100).
    seed : int
        Seed of the runs (``numpy.random.SeedSequence(seed).spawn(repeats)``).
    bottom : str
        Bottom condition of the space to use.
    curve : str, optional
        Replicate id when the file holds several curves of a probe.
    window_focusing : dict, optional
        N, Nb, C, max_iter (``n_samples``, ``n_best``, ``tolerance``, ``max_iter``).
    spaces : dict, optional
        ``{probe_mm: GriddedSpace or NeoHookeanSlice}`` instead of ``space_path``
        (tests, notebooks).
    noise_um : float, optional
        Noise sd of one deflection (µm); by default estimated from replicates of the
        fitted probes, else from differences of the curves (:mod:`skinsuction.noise`).
    level : float
        Confidence level of the profile-likelihood intervals
        (:func:`skinsuction.identify.profile_intervals`).
    thickness : dict, optional
        ``dermis_thickness_mm``, ``hypodermis_thickness_mm`` and their ``_sd_mm``:
        override the file's header lines (:func:`skinsuction.measured.geometry_of`).
    solve_on_demand, workers : bool or "always", int
        Give a probe or layers the scale-free space lacks their neo-Hookean rays
        (:class:`skinsuction.space.OnDemandRays`): read off the geometry space, or
        solved where it does not hold them, in ``workers`` processes; "always"
        solves every one; False refuses such a file.

    Returns
    -------
    Identification
        The estimate (median over the repeats, polished; MPa), its spread, E, the
        profile-likelihood intervals, the fitted curves, the settings, the input
        with its SHA-256 and the warnings; ``to_json()`` is ``identification.json``.
    """
    from skinsuction.measured import MeasuredData, check_against_space, geometry_of, load_measured

    check_settings(alpha, repeats, seed, noise_um, level)
    space = (load_space(space_path, bottom, solve_on_demand=solve_on_demand, workers=workers)
             if spaces is None else LoadedSpace.given(spaces))
    data = measured_path if isinstance(measured_path, MeasuredData) else load_measured(measured_path)
    check_against_space(data, available_probes=space.available_probes)
    geometry, geometry_warnings = geometry_of(data, **(thickness or {}))
    space = space.at(geometry, reads_up_to_mm=fit_reach_mm(data.curves))
    probes_needed = space.check_probes(probes_of(objective, probe_mm, data.probes))
    # the pressures against the space's reach, known once the layers are
    check_against_space(data, available_probes=space.available_probes,
                        pressure_range_mbar=space.pressure_range(probes_needed),
                        range_note=space.range_note(probes_needed))
    result = identify_data(data, space, objective=objective, probe_mm=probe_mm, alpha=alpha,
                           repeats=repeats, seed=seed, curve=curve,
                           window_focusing=window_focusing, noise_um=noise_um, level=level,
                           geometry=geometry)
    result.warnings = geometry_warnings + result.warnings
    result.input["sha256"] = file_sha256(data.path)
    return result


def identify_data(data, space: LoadedSpace, *, objective: str = "single", probe_mm: float = 6.0,
                  alpha: float = 0.5, repeats: int = 100, seed: int = 0,
                  curve: str | None = None, window_focusing: dict | None = None,
                  noise_um: float | None = None, level: float = 0.95,
                  geometry=None) -> Identification:
    """Identify (X1d, X1h) of loaded curves (:class:`skinsuction.measured.MeasuredData`).

    The work of :func:`identify_measured` once the file and the space are read.  A
    study reads the space once (:func:`skinsuction.space.load_space`) and calls
    this for every measurement.  The steps (:mod:`._ramp_steps`): read and check,
    fit, bounds, the runs' spread, intervals, thickness sd, the result.

    Parameters
    ----------
    data : MeasuredData
        The measured curves (:func:`skinsuction.measured.load_measured`).
    space : LoadedSpace
        The simulated space (:func:`skinsuction.space.load_space`).
    objective, probe_mm, alpha, repeats, seed, curve, window_focusing, noise_um, level
        As in :func:`identify_measured`.
    geometry : Geometry, optional
        The layers; by default the file's header, else the paper's 1 mm (warned).

    Returns
    -------
    Identification
        As :func:`identify_measured`'s, with ``input["sha256"]`` None.

    Examples
    --------
    Both probes of a noisy curve of the analytic surrogate (a stand-in for the
    FE space), with the 95 % intervals from a given noise level:

    >>> import numpy as np
    >>> from skinsuction.identify import analytic_surrogate_space
    >>> from skinsuction.measured import MeasuredCurve, MeasuredData
    >>> from skinsuction.space import LoadedSpace, evaluate
    >>> spaces = {p: analytic_surrogate_space(p) for p in (2.0, 6.0)}
    >>> rng = np.random.default_rng(0)
    >>> curves = []
    >>> for p, s in spaces.items():
    ...     m = evaluate(s, [[0.03, 0.0005]])[0] + rng.normal(0, 1e-3, s.pressure_mbar.size)
    ...     curves.append(MeasuredCurve(p, s.pressure_mbar, m))
    >>> r = identify_data(MeasuredData("example", tuple(curves)), LoadedSpace.given(spaces),
    ...                   objective="weighted", repeats=2, noise_um=1.0)
    >>> iv = r.intervals["X1d"]
    >>> bool(iv["lower"] < 0.03 < iv["upper"]), iv["lower_open"] or iv["upper_open"]
    (True, False)
    """
    check_settings(alpha, repeats, seed, noise_um, level)
    setup = setup_ramp(data, space, objective=objective, probe_mm=probe_mm, alpha=alpha,
                       curve=curve, geometry=geometry)
    wf = {**RAMP_WF, **(window_focusing or {})}
    runs = run_ramp(setup, wf, repeats, seed)
    flags = flag_bounds(setup, runs)
    spread = spread_of(setup, runs, wf["max_iter"])
    noise, intervals = noise_and_intervals(setup, runs.theta, noise_um, float(level),
                                           SPACE_ERROR_CORRELATED)
    thickness, est = thickness_uncertainty(setup, runs.theta, runs.est, intervals,
                                           float(level), noise)
    runs = dataclasses.replace(runs, est=est)
    settings = {
        "objective": objective,
        "probe_mm": float(probe_mm) if objective == "single" else None,
        "alpha": float(alpha) if objective == "weighted" else None,
        "repeats": int(repeats),
        "seed": int(seed),
        "window_focusing": wf,
        "excluded_pressures_mbar": (setup.obj.excluded_pressures_mbar.tolist()
                                    if objective == "ratio" else []),
    }
    return _identification(setup, runs, settings, flags, spread, noise, intervals, thickness)


def _identification(setup: RampSetup, runs: RampRuns, settings, flags, spread, noise,
                    intervals, thickness) -> Identification:
    """The result of the steps, in the order of ``identification.json``."""
    from skinsuction import __version__

    obj, rep, runs_mpa, est, best = setup.obj, runs.rep, runs.runs_mpa, runs.est, runs.best
    data, space, scale_free = setup.data, setup.space, setup.scale_free
    return Identification(
        skinsuction_version=__version__,
        created_utc=_dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        input={
            "path": str(data.path),
            "sha256": None,
            "metadata": dict(data.metadata),
            "curves": {f"{p:g}": {"curve": c.curve, "first_line": c.first_line, "points": len(c)}
                       for p, c in setup.curves.items()},
        },
        space={**space.info,
               "bottom": space.bottom,
               "kind": "scale_free" if scale_free else "grid",
               **bounds_json(obj, scale_free),
               "grid": {f"{p:g}": list(s.shape) for p, s in setup.spaces.items()
                        if hasattr(s, "shape")}},
        settings=settings,
        estimate={"x1d_mpa": float(est[0]), "x1h_mpa": float(est[1]),
                  "statistic": "median over the repeats, polished by bounded least "
                               "squares within the space",
                  "window_focusing_median_mpa": [float(runs.wf_est[0]), float(runs.wf_est[1])]},
        at_bound={f["parameter"]: f for f in flags},
        best_run={"x1d_mpa": float(runs_mpa[best, 0]),
                  "x1h_mpa": float(runs_mpa[best, 1]), "E": float(rep.E[best])},
        spread=spread,
        E={"at_estimate": runs.e_est, "median_over_runs": float(np.median(rep.E)),
           "unit": obj.error_unit,
           "definition": "eq. 7, (1/u) sqrt(sum of squared residuals)"},
        iterations={"median": float(np.median(rep.iterations)),
                    "max": int(rep.iterations.max()),
                    "converged_fraction": float(rep.converged.mean())},
        noise=noise,
        intervals=intervals,
        geometry={**setup.geometry.to_dict(), "notes": space.notes(setup.probes),
                  "thickness_uncertainty": thickness},
        fit=fit_records(setup, runs.theta),
        runs=[{"x1d_mpa": float(x[0]), "x1h_mpa": float(x[1]), "E": float(e),
               "iterations": int(n)}
              for x, e, n in zip(runs_mpa, rep.E, rep.iterations)],
        warnings=setup.warnings,
        skin=Skin.two_layer(float(est[0]), float(est[1]), bottom=space.bottom,
                            **_fitted_layers(setup.geometry, thickness)).to_dict(),
    )


def _fitted_layers(geometry, thickness) -> dict:
    """The layers the estimate was fitted at: the given ones, or those the curves prefer."""
    t = {"t_d": geometry.t_d, "t_h": geometry.t_h}
    for key, name in (("t_d", "dermis_thickness"), ("t_h", "hypodermis_thickness")):
        t[key] = ((thickness or {}).get(name) or {}).get("estimate_at_mm", t[key])
    return t
