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
import math

import numpy as np
from scipy import stats

from skinsuction.errors import InputError
from skinsuction.model import Prony, Skin

from ._diagnose import Settings
from ._stats import bic

__all__ = ["VISCOELASTIC_CREEP", "diagnose_time_data", "diagnose_time_file",
           "untestable_on_ramps", "time_summary_text"]

from ._creep import HYPOTHESIS, VISCOELASTIC_CREEP, untestable_on_ramps


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
    """The skin of a time fit (long-time moduli, the spectrum on both layers if any,
    the elastic cause's parameter if any)."""
    spectrum = (Prony(parameters["g"], parameters["tau_s"]) if parameters.get("g")
                else Prony())
    skin = Skin.two_layer(parameters["X1d"], parameters["X1h"], t_d=geometry.t_d,
                          t_h=geometry.t_h, bottom=bottom, spectrum=spectrum)
    if cause is not None:
        skin = skin.replace({path: parameters[cause.symbol] for path in cause.paths})
    return skin.to_dict()


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


def _causes_tried(space, settings, thickness_given) -> list:
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
    js["intervals"] = laplace_intervals(m.rays, fd, m.fit, level=settings.level)
    return js


def diagnose_time_data(data, space, settings: Settings | None = None, *, thickness=None,
                       probes=None, curve=None) -> dict:
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

    Returns
    -------
    dict
        JSON-able: ``effects`` (the effects named, in the order added; [] for
        none), ``cause`` and ``named`` (the first of them, or ``none``),
        ``verdict`` (``cause_found``, ``neo_hookean_fits``, ``unexplained_misfit``: the
        elastic model misfits and no effect earns its place, or ``beyond_space``: the
        model it stands on sits at an edge of the space), ``steps`` (each
        step's options, effect added and ties), ``removed``, ``final`` (its fit,
        intervals and skin), ``elastic`` and ``viscoelastic`` fits (parameters,
        chi^2, BIC, misfit p, chi^2 and RMS per phase), ``gain`` (of the final
        model over the elastic one), ``intervals`` of the viscoelastic fit,
        ``patterns`` (what no model explains, in words), ``summary``,
        ``warnings``, ``geometry``, ``input``.
    """
    from skinsuction import __version__
    from skinsuction.identify import IdentificationError, laplace_intervals
    from skinsuction.identify.time_curves import prepare_time_fit
    from skinsuction.provenance import collect

    from ._time_effects import (CREEP_SECOND_TERM, EffectFitter, cycle_pattern, layer_test,
                                physical_effects, select_effects)

    settings = settings or Settings()
    prep = prepare_time_fit(data, space, probes=probes, curve=curve,
                            noise_um=settings.noise_um, thickness=thickness)
    fd, warnings = prep["data"], list(prep["warnings"])
    try:
        fitter = EffectFitter(prep, settings, _causes_tried(prep["space"], settings, thickness))
        sel = select_effects(fitter, settings)
        visco = fitter.fit((VISCOELASTIC_CREEP,))
    except IdentificationError as err:
        raise InputError(f"{data.path}: beyond the simulated space: {err}") from None
    base, final = sel["base"], sel["final"]
    creep_layers = (layer_test(fitter, final, settings) if settings.layer_test
                    else {"tested": False, "reason": "not asked (layer_test off)"})
    el, ve = _fit_json(base.fit, fd, "elastic"), _fit_json(visco.fit, fd, VISCOELASTIC_CREEP)
    for js in (el, ve):
        js["skin"] = _skin_of(js["parameters"], prep["geometry"], prep["space"].bottom)
    cause_of = {None: None, **{n: fitter.rays[n][fitter.probes[0]].cause
                               for n in fitter.causes}}
    check = creep_layers.get("elastic_check")
    if check is not None and not check["earns_its_place"]:
        # the elastic effect was the shared spectrum's stand-in for a layer's own creep:
        # the final model is the one without it (its spectrum per layer in creep_layers)
        sel["removed"].append({"effect": check["effect"],
                               "delta_bic_without": check["delta_bic_without"],
                               "reason": "a spectrum per layer explains what it was added "
                                         "for"})
        final = fitter.fit(tuple(e for e in final.effects if e != check["effect"]))
        sel["chain"].append(final)
    fin = _model_json(final, fd, prep, settings, cause_of[final.elastic_cause])
    effects = physical_effects(final.effects)
    named = effects[0] if effects else "none"
    misfit = el["misfit_p"] < settings.alpha
    verdict = ("cause_found" if effects else
               "unexplained_misfit" if misfit else "neo_hookean_fits")
    intervals = laplace_intervals(visco.rays, fd, visco.fit, level=settings.level)
    at_bound = _bound_flags(fd, (("elastic", base, el), ("viscoelastic", visco, ve))
                            + ((("final", final, fin),) if effects else ()), warnings)
    # never a silent bound: the model the verdict stands on must not sit at an edge
    standing = "final" if effects else "elastic"
    beyond = [{"model": (final if effects else base).name, "parameter": name}
              for name in at_bound.get(standing, [])]
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
                        f"{min(o['delta_bic'] for o in sel['steps'][0]['options']):+.1f} > "
                        f"{settings.delta_bic:g}): unexplained misfit")
    warnings += [f"pattern: {p}" for p in patterns]
    steps = _steps_json(sel, fitter, fd, prep, settings, cause_of)
    chain = [m.name for m in sel["chain"]]
    fitted_models = {m.name: m for m in sel["chain"]}
    fitted_models[visco.name] = visco
    report = {
        "kind": "time curves",
        "skinsuction_version": __version__,
        "created_utc": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "verdict": verdict, "named": named, "cause": named, "effects": effects,
        "creep_terms": final.terms,
        "causes": {VISCOELASTIC_CREEP: {"hypothesis": HYPOTHESIS,
                                        "parameters": ["g", "tau_s"]},
                   CREEP_SECOND_TERM: {"hypothesis": "the spectrum has two terms (a fast "
                                       "and a slow creep), a refinement of creep",
                                       "parameters": ["g_2", "tau_2"]},
                   **{n: {"hypothesis": c.hypothesis, "parameters": [c.symbol]}
                      for n, c in cause_of.items() if n is not None}},
        "steps": steps, "removed": sel["removed"], "chain": chain, "final": fin,
        "creep_layers": creep_layers,
        "ambiguous_with": sorted({e for s in steps for e in s["ambiguous_with"]}),
        "elastic": el, "viscoelastic": ve,
        "gain": _gain(el, ve, fin if effects else ve),
        "intervals": intervals,
        "patterns": patterns,
        "decision": {"alpha": settings.alpha, "delta_bic": settings.delta_bic,
                     "ambiguity_bic": settings.ambiguity_bic, "elastic_misfits": bool(misfit),
                     "causes_tried": fitter.causes},
        "at_bound": at_bound, "beyond_space": beyond,
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
        "warnings": warnings,
        "fit": {d.label: {"time_s": d.time_s.tolist(),
                          "measured_mm": d.deflection_mm.tolist(),
                          "elastic_mm": np.asarray(m0, float).tolist(),
                          "viscoelastic_mm": np.asarray(m1, float).tolist(),
                          "models": {name: np.asarray(m.fit.fitted_mm[k], float).tolist()
                                     for name, m in fitted_models.items()}}
                for k, (d, m0, m1) in enumerate(zip(fd, base.fit.fitted_mm,
                                                    visco.fit.fitted_mm))},
    }
    report["summary"] = time_summary_text(report)
    return report


def _steps_json(sel, fitter, fd, prep, settings, cause_of) -> list:
    """The steps of the selection, each added effect with its model's parameters and
    intervals."""
    out = []
    chain = sel["chain"]
    for k, step in enumerate(sel["steps"]):
        rec = dict(step)
        if step["added"] is not None:
            m = chain[k + 1]
            js = _model_json(m, fd, prep, settings, cause_of[m.elastic_cause])
            rec["model"] = {key: js[key] for key in ("model", "effects", "parameters",
                                                       "intervals", "chi2", "bic",
                                                       "reduced_chi2", "misfit_p", "skin")}
        out.append(rec)
    return out


def _params_text(params: dict, intervals: dict | None = None) -> str:
    """``X1d = 0.05 [0.048, 0.052] MPa, ...`` of a fit."""
    out = []
    keys = [k for k in params if not k.endswith("instantaneous") and k not in ("g", "tau_s")]
    iv = intervals or {}
    for k in keys:
        v = params[k]
        r = iv.get(k) if isinstance(iv.get(k), dict) else None
        out.append(f"{k} = {v:.4g}" + (f" [{r['lower']:.3g}, {r['upper']:.3g}]" if r else ""))
    for i, (g, tau) in enumerate(zip(params.get("g") or [], params.get("tau_s") or []), 1):
        rg, rt = iv.get(f"g_{i}"), iv.get(f"tau_{i}")
        out.append(f"g = {g:.3g}" + (f" [{rg['lower']:.3g}, {rg['upper']:.3g}]" if rg else "")
                   + f", tau = {tau:.3g} s"
                   + (f" [{rt['lower']:.3g}, {rt['upper']:.3g}]" if rt else ""))
    return ", ".join(out)


def time_summary_text(report: dict) -> str:
    """A few lines for the terminal and report.md: the elastic fit, each step of the
    model, the effects named."""
    el, ve = report["elastic"], report["viscoelastic"]
    p = ve["parameters"]
    lines = []
    assumed = (report.get("geometry") or {}).get("assumptions") or []
    if assumed:
        lines.append("ASSUMED: " + "; ".join(assumed))
    lines.append(f"Elastic fit: X1d = {el['parameters']['X1d']:.4g} MPa, X1h = "
                 f"{el['parameters']['X1h']:.4g} MPa, chi^2/dof = {el['reduced_chi2']:.3g} "
                 f"(misfit p = {el['misfit_p']:.2g}).")
    lines.append(f"Creep alone: X1d = {p['X1d']:.4g} MPa, X1h = {p['X1h']:.4g} MPa "
                 f"(long-time), g = {p['g'][0]:.3g}, tau = {p['tau_s'][0]:.3g} s, chi^2/dof = "
                 f"{ve['reduced_chi2']:.3g}; BIC {ve['bic'] - el['bic']:+.1f}.")
    for step in report.get("steps", []):
        if step["added"] is None:
            best = min(step["options"], key=lambda o: o["bic"])
            lines.append(f"Step {step['step']}: nothing added (best {best['model']}: BIC "
                         f"{best['delta_bic']:+.1f} against {step['from']}"
                         + (", which does not misfit" if step["from_misfit_p"] >= report[
                             "decision"]["alpha"] else "") + ").")
            continue
        opt = next(o for o in step["options"] if o["effects"][-1] == step["added"])
        m = step["model"]
        tie = (f"; tied with {', '.join(step['ambiguous_with'])}" if step["ambiguous_with"]
               else "")
        lines.append(f"Step {step['step']}: + {step['added']} (chi^2 {opt['delta_chi2']:+.1f}, "
                     f"BIC {opt['delta_bic']:+.1f}{tie}): "
                     f"{_params_text(m['parameters'], m['intervals'])}.")
    for r in report.get("removed", []):
        why = r.get("reason", "it no longer earns its place in the final model")
        lines.append(f"Removed {r['effect']}: {why} (BIC {r['delta_bic_without']:+.1f} "
                     "without it).")
    for label, names in (report.get("at_bound") or {}).items():
        lines.append(f"AT BOUND: the {label} fit's {', '.join(names)} at an edge of the space "
                     "or the spectrum (see the warnings): a bound, not an estimate.")
    effects = report.get("effects", [])
    if not effects:
        lines.append("cause none: the elastic model explains the time curves (no effect "
                     "beyond the noise)" if not report["decision"]["elastic_misfits"] else
                     "cause none: the elastic model misfits, but no effect explains it")
    else:
        fin = report["final"]
        lines.append(f"effects {', '.join(effects)}: final model chi^2/dof = "
                     f"{fin['reduced_chi2']:.3g} (misfit p = {fin['misfit_p']:.2g})")
        if effects == [VISCOELASTIC_CREEP]:
            lines.append(f"cause {VISCOELASTIC_CREEP}: the skin creeps; the elastic model "
                         "misses it and a relaxation spectrum fits")
    cl = report.get("creep_layers") or {}
    if cl.get("tested"):
        p, iv = cl["parameters"], cl["intervals"]
        lines.append(f"Which layer creeps: {cl['creeping']} (a spectrum per layer, BIC "
                     f"{cl['delta_bic']:+.1f} against one for both"
                     + (", decisive" if cl["decisive"] else "") + "): dermis g = "
                     f"{p['g_dermis'][0]:.3g} [{iv['g_dermis']['lower']:.3g}, "
                     f"{iv['g_dermis']['upper']:.3g}], hypodermis g = {p['g_hypodermis'][0]:.3g} "
                     f"[{iv['g_hypodermis']['lower']:.3g}, {iv['g_hypodermis']['upper']:.3g}].")
    elif report.get("effects") and VISCOELASTIC_CREEP in report["effects"]:
        lines.append(f"Which layer creeps: not tested: {cl.get('reason')}.")
    if report.get("beyond_space"):
        lines.append("verdict beyond_space: the model sits at an edge of the simulated space "
                     "(" + ", ".join(b["parameter"] for b in report["beyond_space"])
                     + "): the effects named are those of the nearest simulated skin")
    for pat in report.get("patterns", []):
        lines.append(f"Not explained: {pat}.")
    return "\n".join(lines)


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


def write_time_report(report: dict, out_dir) -> dict:
    """``report.json``, ``report.md`` and ``fit.png``/``fit.pdf`` in ``out_dir`` (atomic)."""
    import json
    from pathlib import Path

    from skinsuction._files import atomic_output

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = {"json": out / "report.json", "md": out / "report.md", "png": out / "fit.png",
             "pdf": out / "fit.pdf"}
    _write_text(paths["json"], json.dumps(report, indent=1, default=_json_default) + "\n")
    g = report["gain"]
    other = "final" if report.get("effects") else "viscoelastic"
    other_name = report["final"]["model"] if report.get("effects") else "creep alone"
    md = ["# Diagnosis of time curves", "", f"Input: `{report['input']['path']}`", "",
          "```", report["summary"], "```", "", "## The model, effect by effect", "",
          "| step | from | option | Δχ² | ΔBIC | decisive | added |", "|---|---|---|---|---|---|---|"]
    for step in report.get("steps", []):
        for o in step["options"]:
            md.append(f"| {step['step']} | {step['from']} | {o['model']} | "
                      f"{o['delta_chi2']:+.1f} | {o['delta_bic']:+.1f} | "
                      f"{'yes' if o['decisive'] else 'no'} | "
                      f"{'**yes**' if o['effects'][-1] == step['added'] else ''} |")
    md += ["", f"| curve | phase | RMS elastic (µm) | RMS {other_name} (µm) |", "|---|---|---|---|"]
    for curve, phases in g["rms_um"].items():
        for ph, v in phases.items():
            md.append(f"| {curve} | {ph} | {_fmt(v['elastic'])} | {_fmt(v[other])} |")
    if report["warnings"]:
        md += ["", "## Warnings", ""] + [f"- {w}" for w in report["warnings"]]
    _write_text(paths["md"], "\n".join(md) + "\n")
    _plot(report, paths["png"], paths["pdf"], atomic_output)
    return paths


def _write_text(path, text):
    from skinsuction._files import atomic_output

    with atomic_output(path) as tmp:
        tmp.write_text(text, encoding="utf-8")


def _fmt(v):
    return "-" if v is None else f"{v:.3g}"


def _json_default(o):
    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(type(o).__name__)


def _plot(report, png, pdf, atomic_output):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fits = report["fit"]
    fig, axes = plt.subplots(2, len(fits), figsize=(6 * len(fits), 6), squeeze=False,
                             sharex="col", gridspec_kw={"height_ratios": [3, 1]})
    for k, (label, f) in enumerate(fits.items()):
        t = np.asarray(f["time_s"])
        m = np.asarray(f["measured_mm"])
        ax, rx = axes[0, k], axes[1, k]
        ax.plot(t, m, ".", ms=2, color="0.4", label="measured")
        models = f.get("models") or {"neo_hookean": f["elastic_mm"],
                                     VISCOELASTIC_CREEP: f["viscoelastic_mm"]}
        chain = report.get("chain") or list(models)
        order = chain + [n for n in models if n not in chain]
        for j, name in enumerate(order):
            y = np.asarray(models[name], dtype=float)
            final = bool(report.get("effects")) and name == chain[-1]
            ax.plot(t, y, f"C{j}-", lw=1.6 if final else 0.9,
                    label=name + (" (final)" if final else ""))
            rx.plot(t, 1e3 * (m - y), f"C{j}-", lw=0.9 if final else 0.6)
        ax.set_title(label)
        ax.set_ylabel("deflection (mm)")
        rx.set_ylabel("residual (µm)")
        rx.set_xlabel("time (s)")
        rx.axhline(0.0, color="0.7", lw=0.5)
        ax.legend(fontsize=8)
    fig.suptitle("effects: " + (", ".join(report.get("effects") or []) or "none"))
    fig.tight_layout()
    for path in (png, pdf):
        with atomic_output(path) as tmp:
            fig.savefig(tmp, dpi=120, format=path.suffix[1:])
    plt.close(fig)
