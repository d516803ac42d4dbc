"""The diagnosis of time curves: does the skin's creep explain the elastic model's misfit?

A Cutometer time curve (mode 1: suction on and off; mode 2: a ramp up and down)
holds what a pressure ramp cannot: the deflection keeps rising at a constant
suction, springs back only part of the way on release, and loads and unloads along
different paths.  No elastic model, whatever its cause (stiffening, pre-tension, a
layer thickness), moves at a constant suction: its deflection is a function of the
suction alone.  So on a time curve the candidate is ``viscoelastic_creep``, the
hypothesis that the layers relax (a Prony spectrum over the neo-Hookean layers,
:mod:`skinsuction.viscoelastic`), and the diagnosis compares two fits of the fast
path on the scale-free space (:func:`skinsuction.identify.fit_time_model`):

* the elastic model (g = 0; X1d, X1h), and
* the viscoelastic one (X1d, X1h long-time, one Prony term g, tau).

The decision rule is the pressure-ramp diagnosis's (:mod:`._diagnose`): the
viscoelastic model is named when the elastic fit misfits (chi^2 above its
``1 - alpha`` quantile) and the viscoelastic one is better by the BIC by at least
``|delta_bic|`` (very strong evidence); otherwise ``none``.  Each point's sd is the
identification's: the noise (not below the 0.01 mm quantisation) and the fast
path's measured error per phase (docs/time_identification.md).  The gain is
measured: chi^2, the BIC and the RMS residual per phase, before and after.

On an ascending pressure ramp without time the same creep is a slower or softer
elastic curve: :func:`untestable_on_ramps` says so in every ramp diagnosis.
"""

from __future__ import annotations

import datetime as _dt

import numpy as np
from scipy import stats

from skinsuction.errors import InputError

from ._diagnose import Settings
from ._stats import bic

__all__ = ["VISCOELASTIC_CREEP", "diagnose_time_data", "diagnose_time_file",
           "untestable_on_ramps", "time_summary_text", "write_time_report"]

from ._creep import HYPOTHESIS, VISCOELASTIC_CREEP, untestable_on_ramps
from ._time_report import time_summary_text, write_time_report


def _phase_table(fit, data) -> list:
    out = []
    for d, res, pc in zip(data, fit.residual_um, fit.phase_chi2):
        rec = {"curve": d.label, "probe_mm": d.probe_mm, "phases": {}}
        for ph, (chi2, n) in pc.items():
            sel = (d.phase == ph) & d.used
            rec["phases"][ph] = {"points": int(n), "chi2": float(chi2),
                                 "rms_um": float(np.sqrt(np.mean(res[sel] ** 2)))
                                 if sel.any() else None}
        out.append(rec)
    return out


def _fit_json(fit, data, name) -> dict:
    dof = max(fit.n_points - fit.n_params, 1)
    return {"model": name, "parameters": fit.parameters, "theta": fit.theta.tolist(),
            "chi2": float(fit.chi2), "points": int(fit.n_points), "n_params": int(fit.n_params),
            "reduced_chi2": float(fit.chi2 / dof),
            "misfit_p": float(stats.chi2.sf(fit.chi2, dof)),
            "bic": bic(fit.chi2, fit.n_params, fit.n_points),
            "phases": _phase_table(fit, data)}


def _skin_of(parameters, geometry, bottom, cause=None) -> dict:
    """The skin of a time fit as a dict (:func:`skinsuction.identify.time_fit_skin`)."""
    from skinsuction.identify import time_fit_skin

    return time_fit_skin(parameters, geometry, bottom, cause).to_dict()


def _bound_flags(fd, models, warnings) -> dict:
    """Each model's at-bound flags (stored in its JSON), a loud warning for each."""
    from skinsuction.identify import time_bound_flags

    keys = [("scale_free_space.load.max (the largest suction over load.max sets the lowest "
             "X1d)", "scale_free_space.x1d_mpa.max"),
            ("scale_free_space.ratio", "scale_free_space.ratio")]
    at_bound = {}
    for label, m, js in models:
        flags = time_bound_flags(m.rays, fd, m.fit, keys)
        js["at_bound"] = flags
        for name, fl in flags.items():
            if fl["at_bound"] and not fl.get("neutral"):
                at_bound.setdefault(label, []).append(name)
                warnings.append(f"AT BOUND: the {label} fit's {name} sits at the {fl['side']} "
                                f"edge of the {'spectrum' if name[:2] in ('g_', 'ta') else 'space'}"
                                f" ({fl['edge']}): widen {fl['config_key']}; its value is "
                                "a bound, not an estimate")
    return at_bound


def _undetermined(js: dict, name: str) -> bool:
    """A parameter at an edge that the curves do not hold there (``flat``) and whose
    interval is open at both ends: where it sits is no estimate, and no edge either."""
    flag = (js.get("at_bound") or {}).get(name) or {}
    iv = (js.get("intervals") or {}).get(name) or {}
    return bool(flag.get("flat") and iv.get("lower_open") and iv.get("upper_open"))


def _gain(el, ve, fin) -> dict:
    """What the final model gains over the elastic one (BIC, chi^2), and the RMS of
    each phase of each curve: elastic, creep alone, final model."""
    gain = {"delta_bic": float(fin["bic"] - el["bic"]),
            "delta_chi2": float(fin["chi2"] - el["chi2"]), "model": fin["model"],
            "rms_um": {}}
    for a, b, c in zip(el["phases"], ve["phases"], fin["phases"]):
        gain["rms_um"][a["curve"]] = {ph: {"elastic": a["phases"][ph]["rms_um"],
                                           "viscoelastic": b["phases"][ph]["rms_um"],
                                           "final": c["phases"][ph]["rms_um"]}
                                      for ph in a["phases"]}
    return gain


def _misfit_left(model, fd, settings) -> list:
    """Words for the misfit the final model leaves: the phases whose chi^2 per point
    exceeds its 1 - alpha quantile, with their RMS (µm)."""
    if model.misfit_p >= settings.alpha:
        return []
    out = []
    for d, res, pc in zip(fd, model.fit.residual_um, model.fit.phase_chi2):
        bad = []
        for ph, (chi2, n) in pc.items():
            if n and stats.chi2.sf(chi2, n) < settings.alpha:
                sel = (d.phase == ph) & d.used
                bad.append(f"{ph} (RMS {float(np.sqrt(np.mean(res[sel] ** 2))):.1f} µm, "
                           f"chi^2/n {chi2 / n:.2g})")
        if bad:
            out.append(f"{d.label}: the final model {model.name} still misses "
                       + ", ".join(bad))
    return out


def _causes_tried(space, settings) -> list:
    """The elastic causes a time diagnosis tries (Settings.time_causes, else all)."""
    names = space.cause_names()
    wanted = names if settings.time_causes is None else list(settings.time_causes)
    unknown = [c for c in wanted if c not in names]
    if unknown:
        raise InputError(f"time_causes: no rays for {', '.join(unknown)} beside the space "
                         f"(causes: {', '.join(names) or 'none'})")
    return wanted


def _model_json(m, fd, prep, settings, rays_cause) -> dict:
    from skinsuction.identify import laplace_intervals

    js = _fit_json(m.fit, fd, m.name)
    js["effects"] = list(m.effects)
    js["skin"] = _skin_of(js["parameters"], prep["geometry"], prep["space"].bottom, rays_cause)
    # with the FE correction, the intervals hold the fast path's error at the fit
    js["intervals"] = laplace_intervals(m.rays, m.data or fd, m.fit, level=settings.level)
    js["fe_correction"] = m.correction
    return js


def diagnose_time_data(data, space, settings: Settings | None = None, *, thickness=None,
                       probes=None, curve=None, creep=None) -> dict:
    """Diagnose loaded time curves (:class:`skinsuction.measured.MeasuredTimeData`).

    The model is built effect by effect (:func:`._time_effects.select_effects`):
    creep and each elastic cause of the space, added while decisive, each checked
    against the final model.

    Parameters
    ----------
    data : MeasuredTimeData
    space : LoadedSpace
        The scale-free space (:func:`skinsuction.space.load_space`); its causes'
        rays beside it give the elastic effects.
    settings : Settings
        ``alpha``, ``delta_bic``, ``ambiguity_bic``, ``repeats``, ``seed``,
        ``noise_um``, ``level``, ``time_causes`` are used.
    thickness : dict, optional
        Layer thicknesses overriding the file's header.
    creep : FittedTimeModel, optional
        A fit of one Prony term to the same curves, FE-corrected as the settings ask
        (:attr:`TimeIdentification.fitted <skinsuction.identify.TimeIdentification>`
        of the same file): taken as the creep model instead of fitting it again (a
        study identifies and diagnoses each curve: two FE time solves fewer).  Where
        it was fitted to other points, weights or steps, it is not used.

    Returns
    -------
    dict
        JSON-able: ``effects`` (the effects named, in the order added; [] for
        none), ``cause`` and ``named`` (the first of them, or ``none``),
        ``verdict`` (``cause_found``, ``neo_hookean_fits``, ``unexplained_misfit``: the
        elastic model misfits and no effect earns its place, or ``beyond_space``: the
        model it stands on sits at an edge of the space; not for a parameter the
        curves do not determine at all, listed in ``undetermined``), ``steps`` (each
        step's options, effect added and ties), ``removed``, ``final`` (its fit,
        intervals and skin), ``elastic`` and ``viscoelastic`` fits (parameters,
        chi^2, BIC, misfit p, chi^2 and RMS per phase), ``gain`` (of the final
        model over the elastic one), ``intervals`` of the viscoelastic fit,
        ``patterns`` (what no model explains, in words), ``summary``,
        ``warnings``, ``geometry``, ``input``.
    """
    from skinsuction.identify.time_curves import prepare_time_fit

    settings = settings or Settings()
    prep = prepare_time_fit(data, space, probes=probes, curve=curve,
                            noise_um=settings.noise_um, thickness=thickness)
    run = _select(data, prep, settings, creep)
    judged = _judge(run, prep["data"], settings, list(prep["warnings"]))
    report = _assemble(data, prep, settings, run, judged)
    report["summary"] = time_summary_text(report)
    return report


class _Run:
    """The fits of one diagnosis: the selection, creep alone, the layer test, and the
    JSON of each model (cached: a model's intervals are computed once)."""

    def __init__(self, fitter, sel, visco, creep_layers, prep, settings):
        self.fitter, self.sel, self.visco, self.creep_layers = fitter, sel, visco, creep_layers
        self.base, self.final = sel["base"], sel["final"]
        self.cause_of = {None: None, **{n: fitter.rays[n][fitter.probes[0]].cause
                                        for n in fitter.causes}}
        self._prep, self._settings, self._json = prep, settings, {}

    def model_json(self, m) -> dict:
        if m.name not in self._json:
            self._json[m.name] = _model_json(m, self._prep["data"], self._prep, self._settings,
                                             self.cause_of[m.elastic_cause])
        return self._json[m.name]


def _select(data, prep, settings, creep=None) -> _Run:
    """The effects (:func:`select_effects`), creep alone, which layer creeps, and an
    elastic effect dropped when a spectrum per layer explains it."""
    from skinsuction.identify import IdentificationError

    from ._time_effects import EffectFitter, select_effects
    from ._time_layers import layer_test

    try:
        fitter = EffectFitter(prep, settings, _causes_tried(prep["space"], settings),
                              creep=creep)
        sel = select_effects(fitter, settings)
        visco = fitter.fit((VISCOELASTIC_CREEP,))
    except IdentificationError as err:
        raise InputError(f"{data.path}: beyond the simulated space: {err}") from None
    creep_layers = (layer_test(fitter, sel["final"], settings) if settings.layer_test
                    else {"tested": False, "reason": "not asked (layer_test off)"})
    check = creep_layers.get("elastic_check")
    if check is not None and not check["earns_its_place"]:
        # the elastic effect was the shared spectrum's stand-in for a layer's own creep:
        # the final model is the one without it (its spectrum per layer in creep_layers)
        sel["removed"].append({"effect": check["effect"],
                               "delta_bic_without": check["delta_bic_without"],
                               "reason": "a spectrum per layer explains what it was added "
                                         "for"})
        sel["final"] = fitter.fit(tuple(e for e in sel["final"].effects
                                        if e != check["effect"]))
        sel["chain"].append(sel["final"])
    return _Run(fitter, sel, visco, creep_layers, prep, settings)


def _judge(run: _Run, fd, settings, warnings) -> dict:
    """The verdict, the edges, what is left unexplained, and the warnings."""
    from ._time_effects import physical_effects
    from ._time_layers import cycle_pattern

    base, visco, final = run.base, run.visco, run.final
    el, ve = _fit_json(base.fit, fd, "elastic"), _fit_json(visco.fit, fd, VISCOELASTIC_CREEP)
    ve["fe_correction"] = visco.correction
    fin = run.model_json(final)
    effects = physical_effects(final.effects)
    misfit = el["misfit_p"] < settings.alpha
    verdict = ("cause_found" if effects else
               "unexplained_misfit" if misfit else "neo_hookean_fits")
    at_bound = _bound_flags(fd, (("elastic", base, el), ("viscoelastic", visco, ve))
                            + ((("final", final, fin),) if effects else ()), warnings)
    # never a silent bound: the model the verdict stands on must not sit at an edge,
    # unless the curves do not determine that parameter at all (said as loudly)
    standing = "final" if effects else "elastic"
    undetermined = [name for name in at_bound.get(standing, [])
                    if _undetermined(fin if effects else el, name)]
    beyond = [{"model": (final if effects else base).name, "parameter": name}
              for name in at_bound.get(standing, []) if name not in undetermined]
    for name in undetermined:
        warnings.append(f"UNDETERMINED: the {standing} model's {name} is not determined by "
                        "these curves: its interval spans the whole space (open at both "
                        "ends), and a decade inward of the edge it sits at changes chi^2 by "
                        "less than 1; the verdict does not stand on it (a second, larger "
                        "probe determines the hypodermis)")
    if beyond:
        verdict = "beyond_space"
        warnings.append(f"BEYOND SPACE: the {standing} model sits at an edge of the space or "
                        f"the spectrum ({', '.join(b['parameter'] for b in beyond)}): its "
                        "effects and parameters are those of the nearest simulated skin, not "
                        "an estimate; widen the space where the warnings say")
    patterns = cycle_pattern(fd, final.fit.fitted_mm) + _misfit_left(final, fd, settings)
    if effects and fin["misfit_p"] < settings.alpha:
        warnings.append(f"the final model {final.name} still misfits (chi^2 {fin['chi2']:.4g} "
                        f"on {fin['points']} points, p = {fin['misfit_p']:.2g}): its effects "
                        "explain part of the misfit, not all of it")
    if not effects and misfit:
        warnings.append(f"the elastic fit misfits (p = {el['misfit_p']:.2g}) but no effect "
                        f"earns its parameters (best BIC "
                        f"{min(o['delta_bic'] for o in run.sel['steps'][0]['options']):+.1f} > "
                        f"{settings.delta_bic:g}): unexplained misfit")
    warnings += [f"pattern: {p}" for p in patterns]
    warnings += [f"FE correction: {n}" for n in run.fitter.correction_failures]
    return {"el": el, "ve": ve, "fin": fin, "effects": effects, "misfit": misfit,
            "verdict": verdict, "at_bound": at_bound, "beyond": beyond,
            "undetermined": undetermined,
            "patterns": patterns, "warnings": warnings}


def _assemble(data, prep, settings, run: _Run, j: dict) -> dict:
    """The report of :func:`diagnose_time_data` (its docstring lists the keys)."""
    from skinsuction import __version__
    from skinsuction.identify import laplace_intervals
    from skinsuction.provenance import collect

    from ._time_effects import CREEP_SECOND_TERM

    fd, sel, visco, final, fitter = prep["data"], run.sel, run.visco, run.final, run.fitter
    effects = j["effects"]
    named = effects[0] if effects else "none"
    steps = _steps_json(sel, run)
    fitted_models = {m.name: m for m in sel["chain"]}
    fitted_models[visco.name] = visco
    return {
        "kind": "time curves",
        "skinsuction_version": __version__,
        "created_utc": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "verdict": j["verdict"], "named": named, "cause": named, "effects": effects,
        "creep_terms": final.terms,
        "causes": {VISCOELASTIC_CREEP: {"hypothesis": HYPOTHESIS,
                                        "parameters": ["g", "tau_s"]},
                   CREEP_SECOND_TERM: {"hypothesis": "the spectrum has two terms (a fast "
                                       "and a slow creep), a refinement of creep",
                                       "parameters": ["g_2", "tau_2"]},
                   **{n: {"hypothesis": c.hypothesis, "parameters": [c.symbol]}
                      for n, c in run.cause_of.items() if n is not None}},
        "steps": steps, "removed": sel["removed"],
        "chain": [m.name for m in sel["chain"]], "final": j["fin"],
        "creep_layers": run.creep_layers,
        "ambiguous_with": sorted({e for s in steps for e in s["ambiguous_with"]}),
        "elastic": j["el"], "viscoelastic": j["ve"],
        "gain": _gain(j["el"], j["ve"], j["fin"] if effects else j["ve"]),
        "intervals": laplace_intervals(visco.rays, visco.data or fd, visco.fit,
                                       level=settings.level),
        "patterns": j["patterns"],
        "decision": {"alpha": settings.alpha, "delta_bic": settings.delta_bic,
                     "ambiguity_bic": settings.ambiguity_bic,
                     "elastic_misfits": bool(j["misfit"]), "causes_tried": fitter.causes},
        "at_bound": j["at_bound"], "beyond_space": j["beyond"],
        "undetermined": j["undetermined"],
        "geometry": {**prep["geometry"].to_dict(),
                     "notes": prep["space"].notes(sorted(prep["rays"])) + fitter.notes},
        "input": {"path": str(data.path),
                  "curves": {c.label: {"protocol": c.protocol, "samples": len(c)}
                             for c in prep["curves"]}},
        "provenance": collect(config={"alpha": settings.alpha,
                                      "delta_bic": settings.delta_bic,
                                      "ambiguity_bic": settings.ambiguity_bic,
                                      "time_causes": fitter.causes,
                                      "repeats": settings.repeats, "seed": settings.seed}),
        "warnings": j["warnings"],
        "fit": {d.label: {"time_s": d.time_s.tolist(),
                          "measured_mm": d.deflection_mm.tolist(),
                          "elastic_mm": np.asarray(m0, float).tolist(),
                          "viscoelastic_mm": np.asarray(m1, float).tolist(),
                          "models": {name: np.asarray(m.fit.fitted_mm[k], float).tolist()
                                     for name, m in fitted_models.items()}}
                for k, (d, m0, m1) in enumerate(zip(fd, run.base.fit.fitted_mm,
                                                    visco.fit.fitted_mm))},
    }


def _steps_json(sel, run: _Run) -> list:
    """The steps of the selection, each added effect with its model's parameters and
    intervals."""
    out = []
    for k, step in enumerate(sel["steps"]):
        rec = dict(step)
        if step["added"] is not None:
            js = run.model_json(sel["chain"][k + 1])
            rec["model"] = {key: js[key] for key in ("model", "effects", "parameters",
                                                       "intervals", "chi2", "bic",
                                                       "reduced_chi2", "misfit_p", "skin")}
        out.append(rec)
    return out


def diagnose_time_file(path, space_path=None, settings: Settings | None = None, *,
                       thickness=None, solve_on_demand=True, workers: int = 1) -> dict:
    """:func:`diagnose_time_data` of a file, with the default space if none is given;
    ``path`` may be the file's curves as read
    (:func:`skinsuction.measured.read_measurement`): not read again."""
    from skinsuction._files import file_sha256
    from skinsuction.measured import MeasuredTimeData, load_time_curves
    from skinsuction.space import load_space

    data = path if isinstance(path, MeasuredTimeData) else load_time_curves(path)
    space = load_space(space_path, solve_on_demand=solve_on_demand, workers=workers)
    if space.rays is None:
        raise InputError(f"{space.info['path']}: time curves need the scale-free space (its "
                         "neo-Hookean rays), not a grid database")
    report = diagnose_time_data(data, space, settings, thickness=thickness)
    report["input"]["sha256"] = file_sha256(data.path)
    report["input"]["space"] = space.info
    return report


