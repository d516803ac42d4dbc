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


def _skin_of(parameters, geometry, bottom) -> dict:
    """The skin of a time fit (long-time moduli, the spectrum on both layers, if any)."""
    spectrum = (Prony(parameters["g"], parameters["tau_s"]) if "g" in parameters
                else Prony())
    return Skin.two_layer(parameters["X1d"], parameters["X1h"], t_d=geometry.t_d,
                          t_h=geometry.t_h, bottom=bottom, spectrum=spectrum).to_dict()


def _bound_flags(rays, fd, fits, warnings) -> dict:
    """Each fit's at-bound flags (stored in its JSON), a loud warning for each."""
    from skinsuction.identify import time_bound_flags

    keys = [("scale_free_space.load.max (the largest suction over load.max sets the lowest "
             "X1d)", "scale_free_space.x1d_mpa.max"),
            ("scale_free_space.ratio", "scale_free_space.ratio")]
    at_bound = {}
    for label, fit, js in fits:
        flags = time_bound_flags(rays, fd, fit, keys)
        js["at_bound"] = flags
        for name, fl in flags.items():
            if fl["at_bound"]:
                at_bound.setdefault(label, []).append(name)
                warnings.append(f"AT BOUND: the {label} fit's {name} sits at the {fl['side']} "
                                f"edge of the {'space' if name in ('X1d', 'X1h') else 'spectrum'}"
                                f" ({fl['edge']}): widen {fl['config_key']}; its value is "
                                "a bound, not an estimate")
    return at_bound


def _gain(el, ve, delta_bic) -> dict:
    """What creep gains: BIC, chi^2 and the RMS of each phase of each curve."""
    gain = {"delta_bic": float(delta_bic), "delta_chi2": float(ve["chi2"] - el["chi2"]),
            "rms_um": {}}
    for a, b in zip(el["phases"], ve["phases"]):
        gain["rms_um"][a["curve"]] = {ph: {"elastic": a["phases"][ph]["rms_um"],
                                           "viscoelastic": b["phases"][ph]["rms_um"]}
                                      for ph in a["phases"]}
    return gain


def diagnose_time_data(data, space, settings: Settings | None = None, *, thickness=None,
                       probes=None, curve=None) -> dict:
    """Diagnose loaded time curves (:class:`skinsuction.measured.MeasuredTimeData`).

    Parameters
    ----------
    data : MeasuredTimeData
    space : LoadedSpace
        The scale-free space (:func:`skinsuction.space.load_space`).
    settings : Settings
        ``alpha``, ``delta_bic``, ``repeats``, ``seed``, ``noise_um``, ``level`` are used.
    thickness : dict, optional
        Layer thicknesses overriding the file's header.

    Returns
    -------
    dict
        JSON-able: ``verdict`` (``cause_found`` or ``neo_hookean_fits``), ``named``
        (``viscoelastic_creep`` or ``none``), ``elastic`` and ``viscoelastic`` fits
        (parameters, chi^2, BIC, misfit p, chi^2 and RMS per phase), ``gain``,
        ``intervals`` of the viscoelastic fit, ``summary``, ``warnings``,
        ``geometry``, ``input``.
    """
    from skinsuction import __version__
    from skinsuction.identify import IdentificationError
    from skinsuction.identify import fit_time_model, laplace_intervals
    from skinsuction.identify.time_curves import prepare_time_fit
    from skinsuction.provenance import collect

    settings = settings or Settings()
    prep = prepare_time_fit(data, space, probes=probes, curve=curve,
                            noise_um=settings.noise_um, thickness=thickness)
    rays, fd, warnings = prep["rays"], prep["data"], list(prep["warnings"])
    root = np.random.SeedSequence(int(settings.seed))
    s_el, s_ve = root.spawn(2)
    try:
        elastic = fit_time_model(rays, fd, terms=0, seed=s_el, repeats=settings.repeats)
        # the elastic moduli with a mild spectrum start the viscoelastic polish: nested
        start = np.concatenate([elastic.theta, [math.log10(0.3), math.log10(0.5)]])
        visco = fit_time_model(rays, fd, terms=1, seed=s_ve, repeats=settings.repeats,
                               starts=[start])
    except IdentificationError as err:
        raise InputError(f"{data.path}: beyond the simulated space: {err}") from None
    el, ve = _fit_json(elastic, fd, "elastic"), _fit_json(visco, fd, VISCOELASTIC_CREEP)
    for js in (el, ve):
        js["skin"] = _skin_of(js["parameters"], prep["geometry"], prep["space"].bottom)
    delta_bic = ve["bic"] - el["bic"]
    misfit = el["misfit_p"] < settings.alpha
    named = VISCOELASTIC_CREEP if (misfit and delta_bic <= settings.delta_bic) else "none"
    verdict = "cause_found" if named != "none" else "neo_hookean_fits"
    intervals = laplace_intervals(rays, fd, visco, level=settings.level)
    at_bound = _bound_flags(rays, fd, (("elastic", elastic, el),
                                        ("viscoelastic", visco, ve)), warnings)
    if named != "none" and ve["misfit_p"] < settings.alpha:
        warnings.append(f"the viscoelastic fit still misfits (chi^2 {ve['chi2']:.4g} on "
                        f"{ve['points']} points, p = {ve['misfit_p']:.2g}): creep explains "
                        "part of the misfit, not all of it")
    if named == "none" and misfit:
        warnings.append(f"the elastic fit misfits (p = {el['misfit_p']:.2g}) but creep does "
                        f"not earn its two parameters (BIC {delta_bic:+.1f} > "
                        f"{settings.delta_bic:g}): unexplained misfit")
    gain = _gain(el, ve, delta_bic)
    report = {
        "kind": "time curves",
        "skinsuction_version": __version__,
        "created_utc": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "verdict": verdict, "named": named,
        "causes": {VISCOELASTIC_CREEP: {"hypothesis": HYPOTHESIS,
                                        "parameters": ["g", "tau_s"]}},
        "elastic": el, "viscoelastic": ve, "gain": gain,
        "intervals": intervals,
        "decision": {"alpha": settings.alpha, "delta_bic": settings.delta_bic,
                     "elastic_misfits": bool(misfit)},
        "at_bound": at_bound,
        "geometry": {**prep["geometry"].to_dict(),
                     "notes": prep["space"].notes(sorted(rays))},
        "input": {"path": str(data.path),
                  "curves": {c.label: {"protocol": c.protocol, "samples": len(c)}
                             for c in prep["curves"]}},
        "provenance": collect(config={"alpha": settings.alpha,
                                      "delta_bic": settings.delta_bic,
                                      "repeats": settings.repeats, "seed": settings.seed}),
        "warnings": warnings,
        "fit": {d.label: {"time_s": d.time_s.tolist(),
                          "measured_mm": d.deflection_mm.tolist(),
                          "elastic_mm": np.asarray(m0, float).tolist(),
                          "viscoelastic_mm": np.asarray(m1, float).tolist()}
                for d, m0, m1 in zip(fd, elastic.fitted_mm, visco.fitted_mm)},
    }
    report["summary"] = time_summary_text(report)
    return report


def time_summary_text(report: dict) -> str:
    """A few lines for the terminal and report.md."""
    el, ve = report["elastic"], report["viscoelastic"]
    p = ve["parameters"]
    lines = []
    assumed = (report.get("geometry") or {}).get("assumptions") or []
    if assumed:
        lines.append("ASSUMED: " + "; ".join(assumed))
    lines.append(f"Elastic fit: X1d = {el['parameters']['X1d']:.4g} MPa, X1h = "
                 f"{el['parameters']['X1h']:.4g} MPa, chi^2/dof = {el['reduced_chi2']:.3g} "
                 f"(misfit p = {el['misfit_p']:.2g}).")
    lines.append(f"Viscoelastic fit: X1d = {p['X1d']:.4g} MPa, X1h = {p['X1h']:.4g} MPa "
                 f"(long-time), g = {p['g'][0]:.3g}, tau = {p['tau_s'][0]:.3g} s, chi^2/dof = "
                 f"{ve['reduced_chi2']:.3g}; BIC {report['gain']['delta_bic']:+.1f}.")
    for label, names in (report.get("at_bound") or {}).items():
        lines.append(f"AT BOUND: the {label} fit's {', '.join(names)} at an edge of the space "
                     "or the spectrum (see the warnings): a bound, not an estimate.")
    if report["named"] == "none":
        lines.append("cause none: the elastic model explains the time curves (no creep "
                     "beyond the noise)" if not report["decision"]["elastic_misfits"] else
                     "cause none: the elastic model misfits, but creep does not explain it")
    else:
        lines.append(f"cause {VISCOELASTIC_CREEP}: the skin creeps; the elastic model misses "
                     "it and a relaxation spectrum fits")
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
    md = ["# Diagnosis of time curves", "", f"Input: `{report['input']['path']}`", "",
          "```", report["summary"], "```", "",
          "| curve | phase | RMS elastic (µm) | RMS viscoelastic (µm) |", "|---|---|---|---|"]
    for curve, phases in g["rms_um"].items():
        for ph, v in phases.items():
            md.append(f"| {curve} | {ph} | {_fmt(v['elastic'])} | {_fmt(v['viscoelastic'])} |")
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
        for key, style in (("elastic_mm", "C0-"), ("viscoelastic_mm", "C3-")):
            y = np.asarray(f[key], dtype=float)
            ax.plot(t, y, style, lw=1.2, label=key.replace("_mm", ""))
            rx.plot(t, 1e3 * (m - y), style, lw=0.8)
        ax.set_title(label)
        ax.set_ylabel("deflection (mm)")
        rx.set_ylabel("residual (µm)")
        rx.set_xlabel("time (s)")
        rx.axhline(0.0, color="0.7", lw=0.5)
        ax.legend(fontsize=8)
    fig.suptitle(f"named: {report['named']}")
    fig.tight_layout()
    for path in (png, pdf):
        with atomic_output(path) as tmp:
            fig.savefig(tmp, dpi=120, format=path.suffix[1:])
    plt.close(fig)
