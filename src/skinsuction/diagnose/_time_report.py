"""What a time-curve diagnosis says: the summary lines and the files it writes.

:func:`time_summary_text` gives the lines of the terminal and ``report.md``;
:func:`write_time_report` writes ``report.json``, ``report.md`` and the fit figure of
a report of :func:`skinsuction.diagnose.diagnose_time_data`.
"""

from __future__ import annotations

import numpy as np

from ._creep import VISCOELASTIC_CREEP

__all__ = ["time_summary_text", "write_time_report"]


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
    if report.get("undetermined"):
        lines.append("Not determined by these curves (at an edge only because nothing holds "
                     "them): " + ", ".join(report["undetermined"]) + ".")
    for pat in report.get("patterns", []):
        lines.append(f"Not explained: {pat}.")
    return "\n".join(lines)


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
