"""Identify X1d, X1h and a relaxation spectrum from Cutometer time curves.

What ``skinsuction identify TIME_CURVES.csv`` runs: read the curves
(:func:`skinsuction.measured.load_time_curves`), take the space at the subject's
layers, fit the long-time moduli and one or two Prony terms with the fast path
(:func:`skinsuction.identify._time_fit.fit_time_model`), correct that fit by FE time
solves at it (:func:`skinsuction.identify.fe_corrected_fit`), put Laplace intervals on
every parameter, flag edges, and report the R parameters beside them
(:func:`identify_time_data`: a :class:`~skinsuction.identify.TimeIdentification`);
write ``identification.json`` and a fit figure (:func:`write_time_identification`,
the one writer :func:`skinsuction.identify.write_identification`).

Examples
--------
>>> from skinsuction.measured import load_time_curves
>>> from skinsuction.space import load_space
>>> r = identify_time_data(load_time_curves("data/example_mode1.csv"), load_space(),
...                        terms=1, repeats=1)        # doctest: +SKIP
>>> r.X1d, r.g, r.tau_s                                # doctest: +SKIP
"""

from __future__ import annotations

import datetime as _dt
import math

import numpy as np

from skinsuction._files import file_sha256
from skinsuction.errors import InputError
from skinsuction.model import Prony, Skin

from ._identification import TimeIdentification, write_identification
from ._time_fit import (
    MODEL_ERROR,
    TIME_WF,
    fit_data_of,
    fit_time_model,
)
from ._time_correction import FittedTimeModel
from ._time_intervals import laplace_intervals, time_bound_flags
from ._time_model import G_BOUNDS, TAU_BOUNDS_S
from ._window_focusing import IdentificationError

__all__ = ["identify_time_file", "identify_time_data", "prepare_time_fit", "write_time_identification"]

PHASE_NAMES = ("rest", "on", "release", "off", "ramp")


def _check(terms, repeats, seed, noise_um, level, phases):
    if terms not in (1, 2):
        raise InputError(f"--terms must be 1 or 2 Prony terms, not {terms}")
    if int(repeats) < 1 or int(seed) < 0:
        raise InputError("repeats must be >= 1 and seed >= 0")
    if noise_um is not None and not noise_um > 0:
        raise InputError(f"the noise sd must be positive, not {noise_um} µm")
    if not 0 < level < 1:
        raise InputError(f"the level must lie in (0, 1), not {level}")
    if phases not in ("all", "on"):
        raise InputError(f"phases must be 'all' or 'on', not {phases!r}")


def identify_time_file(path, space_path=None, *, thickness=None, solve_on_demand=True,
                       workers=1, **options) -> TimeIdentification:
    """:func:`identify_time_data` of a file, the space read from ``space_path``.

    Parameters
    ----------
    path : path-like or MeasuredTimeData
        The time-curve CSV, or its curves as read
        (:func:`skinsuction.measured.read_measurement`): not read again.
    space_path : path-like, optional
        The scale-free space (default: :func:`skinsuction.space.load_space`'s).
    thickness : dict, optional
        Layer thicknesses overriding the file's header.
    solve_on_demand : bool or "always"
        Give a probe or layers the space lacks their rays (the geometry space, else
        solved; "always": solved), or refuse them (False).
    workers : int
        Processes for those solves.
    **options
        The settings of :func:`identify_time_data` (``terms``, ``probes`` ...).

    Returns
    -------
    TimeIdentification
        With ``input["sha256"]`` the file's SHA-256.
    """
    from skinsuction.measured import MeasuredTimeData, load_time_curves
    from skinsuction.space import load_space

    data = path if isinstance(path, MeasuredTimeData) else load_time_curves(path)
    space = load_space(space_path, solve_on_demand=solve_on_demand, workers=workers)
    if space.rays is None:
        raise InputError(f"{space.info['path']}: time curves need the scale-free space (its "
                         "neo-Hookean rays), not a grid database")
    result = identify_time_data(data, space, thickness=thickness, **options)
    result.input["sha256"] = file_sha256(data.path)
    return result


def _select(data, probes, curve):
    curves = list(data.curves)
    if probes is not None:
        want = [float(p) for p in probes]
        curves = [c for c in curves if any(math.isclose(c.probe_mm, p, abs_tol=1e-6)
                                           for p in want)]
        missing = [p for p in want if not any(math.isclose(c.probe_mm, p, abs_tol=1e-6)
                                              for c in curves)]
        if missing:
            raise InputError(f"{data.path}: no time curve of the {missing[0]:g} mm probe "
                             f"(probes: {', '.join(f'{p:g}' for p in data.probes)} mm)")
    if curve is not None:
        curves = [c for c in curves if c.curve == str(curve)]
        if not curves:
            raise InputError(f"{data.path}: no time curve named {curve!r}")
    if not curves:
        raise InputError(f"{data.path}: no time curve to fit")
    return curves


def _rparams_records(curves, ue_time_s):
    from skinsuction.measured import r_parameters, ramp_parameters

    out = {"mode1": [], "mode2": []}
    for c in curves:
        try:
            if c.protocol == "mode 1":
                frame = r_parameters(c, ue_time_s=ue_time_s)
                out["mode1"] += frame.to_dict(orient="records")
            elif c.protocol == "mode 2":
                out["mode2"] += ramp_parameters(c).to_dict(orient="records")
        except ValueError as err:
            out.setdefault("notes", []).append(f"{c.label}: {err}")
    return out


def prepare_time_fit(data, space, *, probes=None, curve=None, noise_um=None, phases="all",
                     thickness=None) -> dict:
    """What a fit of loaded time curves needs, checked: shared by identify and diagnose.

    Returns ``{"curves", "rays" (probe -> neo-Hookean RaySpace at the geometry),
    "data" (TimeFitData per curve), "warnings", "geometry", "space" (at the
    geometry)}``; raises :class:`InputError` for a suction beyond the space's reach.
    """
    from skinsuction.measured import geometry_of
    from skinsuction.space import fit_reach_mm

    geometry, warnings = geometry_of(data, **(thickness or {}))
    warnings = list(getattr(data, "warnings", ())) + list(warnings)
    space = space.at(geometry, reads_up_to_mm=fit_reach_mm(data.curves))
    curves = _select(data, probes, curve)
    warnings += [f"geometry: {a}" for a in geometry.assumptions()]
    if any(v for v in (getattr(geometry, "sd", None) or {}).values()):
        warnings.append("geometry: a thickness sd is not propagated into the intervals of "
                        "time curves (the layers are taken as given)")
    rays = {}
    for c in curves:
        rays[c.probe_mm] = space.probe(c.probe_mm).space
    warnings += [f"geometry: {n}" for n in space.notes(sorted(rays))]
    for c in curves:
        if c.protocol not in ("mode 1", "mode 2"):
            warnings.append(f"{c.label}: protocol {c.protocol}: the fast path's error is "
                            "measured on mode 1 and mode 2 only")
    fit_data = []
    for c in curves:
        try:
            fit_data.append(fit_data_of(c, noise_sd_mm=None if noise_um is None
                                        else 1e-3 * noise_um, phases=phases))
        except ValueError as err:
            raise InputError(f"{data.path}: {err}") from None
    for c, d in zip(curves, fit_data):
        spec = rays[c.probe_mm].spec
        p_max = float(d.pressure_mbar.max())
        if p_max > spec.reach_mbar():
            k = int(np.argmax(d.pressure_mbar))
            raise InputError(
                f"{data.path}, line {int(c.lines[k]) if c.lines.size else 0}, column "
                f"pressure_mbar: {c.label}: a suction of {p_max:g} mbar is beyond the reach "
                f"of the scale-free space (p/X1d <= {spec.load_max:g} mbar/MPa up to X1d = "
                f"{spec.x1d_range[1]:g} MPa: at most {spec.reach_mbar():g} mbar)")
    return {"curves": curves, "rays": rays, "data": fit_data, "warnings": warnings,
            "geometry": geometry, "space": space}


def identify_time_data(data, space, *, terms: int = 1, probes=None, curve=None,
                       repeats: int = 2, seed: int = 0, noise_um: float | None = None,
                       level: float = 0.95, phases: str = "all", thickness=None,
                       ue_time_s: float = 0.1,
                       window_focusing: dict | None = None,
                       effect: str | None = None,
                       fe_correction: int = 2) -> TimeIdentification:
    """Identify X1d, X1h (long-time) and ``terms`` Prony terms of loaded time curves.

    The steps: read and check (:func:`prepare_time_fit`), fit
    (:func:`~skinsuction.identify.fit_time_model`), intervals
    (:func:`~skinsuction.identify.laplace_intervals`), bounds and notes
    (:func:`_flag_bounds`, :func:`_interval_notes`), the fit per curve and phase
    (:func:`_fit_quality`), the result (:func:`_time_identification`).

    Parameters
    ----------
    data : MeasuredTimeData
        The time curves (:func:`skinsuction.measured.load_time_curves`).
    space : LoadedSpace
        A scale-free space (:func:`skinsuction.space.load_space`).
    terms : {1, 2}
        Prony terms of the relaxation spectrum.
    probes : list of float, optional
        The probes fitted (default: every curve of the file, jointly: one skin).
    curve : str, optional
        The replicate fitted (column ``curve``).
    repeats, seed : int
        Window focusing runs (seeds spawned from ``seed``), the best polished.
    noise_um : float, optional
        Noise sd of one deflection (default: the loader's, not below q/sqrt(12)).
    level : float
        Confidence level of the intervals.
    phases : {"all", "on"}
        Fit every point with the model-error sd per phase, or only those while the
        suction is on.
    thickness : dict, optional
        Layer thicknesses overriding the file's header (:func:`geometry_of`).
    ue_time_s : float
        When Ue of the R parameters is read after the suction starts (s).
    window_focusing : dict, optional
        Overrides of :data:`TIME_WF` (``n_samples``, ``n_best``, ``tolerance``, ``max_iter``).
    effect : str, optional
        An elastic cause fitted with the spectrum (e.g. ``"strain_stiffening"``: the
        fast path then drives the stiffening skin's elastic curve, and X2d is
        identified with its interval); its rays must lie beside the space.
    fe_correction : int
        Steps of the FE correction of the fit (FE time solves at the fit remove the
        fast path's error, :func:`~skinsuction.identify.fe_corrected_fit`); 0: the
        fast path alone.

    Returns
    -------
    TimeIdentification
        ``X1d``, ``X1h`` (MPa, long-time), ``g``, ``tau_s`` (lists),
        ``X1d_instantaneous``, ``X1h_instantaneous``, ``intervals``, ``at_bound``,
        ``r_parameters``, ``fit_quality`` (chi^2 per curve and phase), ``fit``
        (curves), ``noise``, ``likelihood``, ``space``, ``geometry``, ``settings``,
        ``input`` (``sha256`` None), ``provenance``, ``warnings``; ``to_json()`` is
        ``identification.json``.
    """
    _check(terms, repeats, seed, noise_um, level, phases)
    _check_steps(fe_correction)
    prep = prepare_time_fit(data, space, probes=probes, curve=curve, noise_um=noise_um,
                            phases=phases, thickness=thickness)
    rays, fit_data, warnings = prep["rays"], prep["data"], prep["warnings"]
    if effect is not None:
        rays, notes = prep["space"].cause_rays(effect, sorted(rays))
        warnings += [f"geometry: {n}" for n in notes]
        if not rays:
            raise InputError(f"{data.path}: the effect {effect} is not free here (see the "
                             "notes: " + "; ".join(notes) + ")")
    wf = {**TIME_WF, **(window_focusing or {})}
    try:
        fit = fit_time_model(rays, fit_data, terms=terms, seed=seed, repeats=repeats,
                             window_focusing_options=wf)
    except IdentificationError as err:
        raise InputError(f"{data.path}: beyond the simulated space: {err}") from None
    # the intervals hold the fast path's error at the fit (the data less it)
    fit, corrected, correction = _corrected(prep, rays, fit_data, fit, fe_correction, seed,
                                            warnings)
    intervals = laplace_intervals(rays, corrected, fit, level=level)
    flags = _flag_bounds(rays, fit_data, fit, intervals, warnings)
    _interval_notes(fit_data, fit, intervals, flags, warnings)
    settings = {"terms": int(terms), "repeats": int(repeats), "seed": int(seed),
                "phases": phases, "level": float(level), "window_focusing": wf,
                "g_bounds": list(G_BOUNDS), "tau_bounds_s": list(TAU_BOUNDS_S),
                "probes_mm": [c.probe_mm for c in prep["curves"]], "curve": curve,
                "ue_time_s": float(ue_time_s), "effect": effect,
                "fe_correction": correction}
    noise = {"sd_um": [1e3 * d.noise_sd_mm for d in fit_data],
             "method": "given" if noise_um is not None else
             "the loader's (third differences in time, not below q/sqrt(12))",
             "resolution_mm": [c.resolution_mm for c in prep["curves"]]}
    result = _time_identification(data, {**prep, "rays": rays}, fit, intervals, flags,
                                  settings, noise)
    result.fitted = FittedTimeModel(fit, corrected, correction, tuple(fit_data),
                                    prep["geometry"], effect)
    return result


def _corrected(prep, rays, fit_data, fit, steps, seed, warnings) -> tuple:
    """``(fit, data, record)``: the fit corrected by FE time solves at the fit, and the
    data less the fast path's error there (:func:`fe_corrected_fit`); the fast fit,
    with a warning, where an FE time solve stops."""
    from ._time_correction import fe_corrected_fit, time_fit_skin

    if _check_steps(steps) == 0:
        return fit, fit_data, {"applied": False, "reason": "not asked (fe_correction 0)"}
    cause = next(iter(rays.values())).cause

    def skin_of(parameters):
        return time_fit_skin(parameters, prep["geometry"], prep["space"].bottom, cause)

    try:
        return fe_corrected_fit(rays, fit_data, fit, skin_of, iterations=steps, seed=seed)
    except RuntimeError as err:
        warnings.append(f"FE correction: stopped ({err}); the fit is the fast path's, with "
                        "its model error")
        return fit, fit_data, {"applied": False, "reason": str(err)}


def _check_steps(steps) -> int:
    if int(steps) != steps or not 0 <= steps <= 5:
        raise ValueError(f"fe_correction must be a whole number of steps in 0..5, got "
                         f"{steps!r}")
    return int(steps)


def _flag_bounds(rays, fit_data, fit, intervals, warnings) -> dict:
    """The ``at_bound`` flags of every parameter, a warning for each at an edge."""
    x1d_lo_key = "scale_free_space.load.max (the largest suction over load.max sets the " \
                 "lowest X1d)"
    flags = time_bound_flags(rays, fit_data, fit, [
        (x1d_lo_key, "scale_free_space.x1d_mpa.max"),
        ("scale_free_space.ratio", "scale_free_space.ratio")])
    for name, f in flags.items():
        if not f["at_bound"]:
            continue
        value = intervals[name]["estimate"]
        if name not in ("X1d", "X1h") and not name.startswith(("g_", "tau_")):
            if not f.get("neutral"):
                warnings.append(f"AT BOUND: {name} = {value:.4g} sits at the {f['side']} end "
                                f"of the simulated range of its cause; widen it with "
                                f"{f['config_key']}")
            continue
        if name in ("X1d", "X1h"):
            where = ("the end of the simulated window" if f["edge"] == "window"
                     else "the coverage frontier (the FE rays stop there: the suction "
                          "exceeds the space's reach for this X1d)")
            warnings.append(f"AT BOUND: {name} = {value:.4g} MPa sits at the {f['side']} edge "
                            f"of the simulated space ({where}); widen it with "
                            f"{f['config_key']}")
        else:
            warnings.append(f"AT BOUND: {name} = {value:.4g}{' s' if 'tau' in name else ''} "
                            f"sits at the {f['side']} end of the spectrum's bounds (g "
                            f"{G_BOUNDS[0]:g}-{G_BOUNDS[1]:g}, tau {TAU_BOUNDS_S[0]:g}-"
                            f"{TAU_BOUNDS_S[1]:g} s): the data may want a value beyond it")
    return flags


def _interval_notes(fit_data, fit, intervals, flags, warnings) -> None:
    """Warn of open intervals, unresolved time constants, a misfit; then the intervals' notes."""
    for name, iv in intervals.items():
        if isinstance(iv, dict) and (iv.get("lower_open") or iv.get("upper_open")) \
                and not flags.get(name.replace("_instantaneous", ""), {}).get("at_bound"):
            warnings.append(f"{name}: the data do not bound it within the space and the "
                            f"spectrum's bounds ({iv['lower']:.3g}-{iv['upper']:.3g}, open)")
    dt = min(float(np.median(np.diff(d.time_s))) for d in fit_data)
    for k, tau in enumerate(fit.parameters["tau_s"], start=1):
        if tau < 2 * dt:
            warnings.append(f"tau_{k} = {1e3 * tau:.3g} ms is shorter than two samples "
                            f"({1e3 * dt:.3g} ms apart): it is seen only through the jump "
                            "of the deflection, not resolved in time")
    if intervals["misfit_scale"] > 1.0:
        warnings.append(f"the residuals are {math.sqrt(intervals['misfit_scale']):.2g} times "
                        "the noise and the fast path's model error: the model (or the "
                        "number of Prony terms) misses the curve; the intervals are widened")
    warnings += intervals["notes"]


def _fit_quality(curves, fit_data, fit):
    """The chi^2 and residuals of each curve per phase, and the curves measured and fitted.

    Returns
    -------
    quality : list of dict
        Per curve: points, chi^2, and per phase chi^2, RMS and largest residual.
    fitted : dict
        Per curve: time, pressure, measured and fitted deflections, residuals, phases.
    """
    quality, fitted = [], {}
    for c, d, m, res, pc in zip(curves, fit_data, fit.fitted_mm, fit.residual_um,
                                fit.phase_chi2):
        rec = {"curve": c.label, "probe_mm": c.probe_mm, "protocol": c.protocol,
               "points": int(d.n), "chi2": float(sum(v[0] for v in pc.values())),
               "phases": {}}
        for ph, (chi2, n) in pc.items():
            sel = d.phase == ph
            rec["phases"][ph] = {
                "points": n, "chi2": chi2, "reduced_chi2": chi2 / n if n else None,
                "rms_um": float(np.sqrt(np.mean(res[sel] ** 2))) if sel.any() else None,
                "max_abs_um": float(np.max(np.abs(res[sel]))) if sel.any() else None,
                "model_error_sd_um": 1e3 * (d.model_error or MODEL_ERROR)[ph] * d.scale_mm,
                "fitted": bool(d.used[sel].any())}
        quality.append(rec)
        fitted[c.label] = {"probe_mm": c.probe_mm, "time_s": d.time_s.tolist(),
                           "pressure_mbar": d.pressure_mbar.tolist(),
                           "measured_mm": d.deflection_mm.tolist(),
                           "fitted_mm": [float(v) if np.isfinite(v) else None for v in m],
                           "residual_um": [float(v) if np.isfinite(v) else None for v in res],
                           "phase": [str(v) for v in d.phase]}
    return quality, fitted


def _time_identification(data, prep, fit, intervals, flags, settings,
                         noise) -> TimeIdentification:
    """The result of the steps, in the order of ``identification.json``."""
    from skinsuction import __version__
    from skinsuction.provenance import collect

    curves, rays, fit_data, geometry, space = (prep["curves"], prep["rays"], prep["data"],
                                               prep["geometry"], prep["space"])
    params, terms, phases = fit.parameters, settings["terms"], settings["phases"]
    cause = next(iter(rays.values())).cause
    skin = Skin.two_layer(params["X1d"], params["X1h"], t_d=geometry.t_d, t_h=geometry.t_h,
                          bottom=space.bottom, spectrum=Prony(params["g"], params["tau_s"]))
    model = {"name": "two-layer neo-Hookean, one Prony spectrum for both layers, fast "
                     "path M_el(p_eff) on the scale-free space",
             "convention": "X1d, X1h long-time (equilibrium) moduli; instantaneous "
                           "X1 (1 + sum g)", "terms": int(terms)}
    if cause is not None:
        skin = skin.replace({path: params[cause.symbol] for path in cause.paths})
        model.update({"name": f"two-layer, {cause.name} ({cause.symbol}), one Prony spectrum "
                              "for both layers, fast path M_el(p_eff) on the cause's rays",
                      "effect": cause.name, cause.symbol: params[cause.symbol]})
    if (settings.get("fe_correction") or {}).get("applied"):
        model["name"] += ", corrected by FE time solves at the fit"
    quality, fitted = _fit_quality(curves, fit_data, fit)
    spec = next(iter(rays.values())).spec
    return TimeIdentification(
        skinsuction_version=__version__,
        created_utc=_dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        model=model,
        X1d=params["X1d"], X1h=params["X1h"], g=params["g"], tau_s=params["tau_s"],
        X1d_instantaneous=params["X1d_instantaneous"],
        X1h_instantaneous=params["X1h_instantaneous"],
        intervals=intervals,
        at_bound=flags,
        r_parameters=_rparams_records(curves, settings["ue_time_s"]),
        fit_quality={"chi2": float(fit.chi2), "points": int(fit.n_points),
                     "parameters": int(fit.n_params),
                     "reduced_chi2": float(fit.chi2 / max(fit.n_points - fit.n_params, 1)),
                     "curves": quality},
        noise=noise,
        likelihood={"sd": "sqrt(noise^2 + (model_error[phase] * U)^2), U the curve's "
                          "largest deflection",
                    "model_error_fraction": {d.label: dict(d.model_error or MODEL_ERROR)
                                             for d in fit_data},
                    "model_error_rule": "max(MODEL_ERROR[phase], STRAIN_SLOPE[phase] * U / "
                                        "(aperture / 2)): the fast path's measured error "
                                        "grows with the strain",
                    "phases_fitted": phases,
                    "pressure": [n for d in fit_data for n in d.notes]},
        space={**space.info, "bottom": space.bottom, "kind": "scale_free",
               "x1d_range_mpa": list(spec.x1d_range), "load_max": spec.load_max,
               "reach_mbar": spec.reach_mbar(),
               "bounds_x1h_over_x1d": [float(spec.ratio_nodes[0]),
                                       float(spec.ratio_nodes[-1])]},
        geometry={**geometry.to_dict(), "notes": space.notes(sorted(rays))},
        settings=settings,
        input={"path": str(data.path), "sha256": None, "metadata": dict(data.metadata),
               "curves": {c.label: {"first_line": c.first_line, "samples": len(c),
                                    "protocol": c.protocol} for c in curves}},
        runs=fit.wf,
        fit=fitted,
        provenance=collect(config=settings),
        warnings=prep["warnings"],
        skin=skin.to_dict(),
    )


def write_time_identification(result: TimeIdentification, out_dir) -> dict:
    """Write ``identification.json`` and ``fit.png`` / ``fit.pdf`` (atomically).

    The one writer of both kinds of result,
    :func:`skinsuction.identify.write_identification`, under the name the time
    curves' callers know.

    Parameters
    ----------
    result : TimeIdentification
        Of :func:`identify_time_data`.
    out_dir : path-like
        The folder (created if missing).

    Returns
    -------
    dict
        ``{"json": path, "png": path, "pdf": path}``.
    """
    return write_identification(result, out_dir)
