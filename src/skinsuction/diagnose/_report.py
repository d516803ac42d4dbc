"""Write a diagnosis: ``report.json``, ``report.md`` and its figures."""

from __future__ import annotations

from pathlib import Path

from skinsuction.results import markdown_table, write_json, write_text

__all__ = ["write_report", "report_markdown"]


def _num(x, fmt=".3g"):
    return "n/a" if x is None else format(x, fmt)


def _params(p):
    return ", ".join(f"{k} = {v:.4g}" for k, v in p.items())


def _interval_rows(model: str, ci) -> list:
    if not ci:
        return []
    if "error" in ci:
        return [f"| {model} | (no intervals: {ci['error']}) | | |"]
    out = []
    for name, iv in ci.items():
        if not isinstance(iv, dict) or "lower" not in iv:
            continue
        lo = ("≤ " if iv["lower_open"] else "") + f"{iv['lower']:.4g}"
        hi = ("≥ " if iv["upper_open"] else "") + f"{iv['upper']:.4g}"
        out.append(f"| {model} | {name} | {iv['estimate']:.4g} | [{lo}, {hi}] |")
    return out


def _space_lines(inp: dict) -> list:
    """The simulated space of the diagnosis, as a list item (none if not recorded)."""
    space = inp.get("space") or {}
    if not space.get("description"):
        return []
    where = f" (`{inp['space_dir']}`)" if inp.get("space_dir") and space.get("source") != "given" \
        else ""
    return [f"- simulated space: {space['description']}{where}"]


def report_markdown(report: dict, figures=None) -> str:
    """The report as Markdown (``report.md``).

    Parameters
    ----------
    report : dict
        The report of :func:`skinsuction.diagnose.diagnose`.
    figures : dict, optional
        ``{name: path}`` of the figures to show (by file name, next to the report).

    Returns
    -------
    str
        Markdown, ending with a newline.
    """
    b = report["baseline"]
    lines = [
        f"# Diagnosis of {Path(report['input'].get('file') or 'the measured curves').name}",
        "",
        f"**Cause: `{report['cause']}`** ({report['verdict'].replace('_', ' ')})"
        + (f"; effects, in the order added: {', '.join(f'`{e}`' for e in report['effects'])}"
           if len(report.get("effects") or ()) > 1 else ""),
        "",
        report["summary"],
        "",
        "## Input",
        "",
        f"- file: `{report['input'].get('file')}` (SHA-256 `{report['input'].get('sha256')}`)",
        f"- probes: {', '.join(f'{p:g} mm' for p in report['input']['probes_mm'])}",
        f"- noise: {report['noise_um']:.3g} µm per deflection ({report['noise']['method']}"
        + (f", {report['noise']['dof']:.0f} degrees of freedom" if report["noise"].get("dof")
           else "") + f"); accuracy of the spaces {report['noise']['model_error_um']:g} µm "
        "added in quadrature",
        *_space_lines(report["input"]),
        *_geometry_lines(report.get("geometry")),
        "",
        "## Neo-Hookean fit (baseline)",
        "",
        f"- {_params(b['parameters'])} (MPa)",
        f"- E = {b['E_um']:.3g} µm (eq. 7), RMS residual {b['rms_um']:.3g} µm, "
        f"chi² = {b['chi2']:.1f} for {b['n_points']} points",
        f"- systematic misfit: **{'yes' if b['systematic_misfit'] else 'no'}** "
        f"(smooth-pattern test p = {b['misfit_test']['p_value']:.2g}, level "
        f"{b['misfit_test']['alpha']:g})",
        f"- {b['description']}",
        "",
        "## Candidate causes",
        "",
        markdown_table([_candidate_cells(c, report)
                        for c in sorted(report["candidates"], key=lambda c: c["bic"])],
                       CANDIDATE_COLUMNS, align=False),
        "",
        f"Baseline cross-probe holdout E: {_num(b.get('holdout_E_um'))} µm.",
        "",
        "Rule: a cause is named if "
        + ("the neo-Hookean residuals carry a systematic pattern, "
           if report["settings"].get("pattern_gate") else "")
        + f"its ΔBIC ≤ {report['settings']['delta_bic']:g} and its own residuals pass the "
        "pattern test; among those the lowest BIC wins, and candidates within "
        f"{report['settings']['ambiguity_bic']:g} of it are reported as a tie."
        + ("" if report["settings"].get("pattern_gate") else
           " The cause's own fit is the detection: the neo-Hookean residuals need not "
           "show a pattern first."),
        "",
    ]
    lines += _second_effect_lines(report)
    rows = _interval_rows("neo_hookean", b.get("intervals"))
    for c in sorted(report["candidates"], key=lambda c: c["bic"]):
        rows += _interval_rows(c["cause"], c.get("intervals"))
    added = (report.get("second_effect") or {}).get("added")
    if added:
        rows += _interval_rows(" + ".join(added["effects"]), added.get("intervals"))
    if rows:
        level = (b.get("intervals") or {}).get("level", 0.95)
        lines += [f"## {100 * level:g} % intervals (profile likelihood)", "",
                  "| model | parameter | estimate | interval |", "|---|---|---|---|", *rows, "",
                  "≤ / ≥: the interval reaches the edge of the simulated space on that side "
                  "(the data do not bound the parameter there). Units: MPa (moduli), mm "
                  "(t_d), 1 (lambda0).", ""]
    if figures:
        lines += ["## Figures", ""]
        for name, path in figures.items():
            lines.append(f"![{name}]({Path(path).name})")
        lines.append("")
    lines.append(f"Run time {report['seconds']:.1f} s; skinsuction {report.get('skinsuction_version')}.")
    return "\n".join(lines) + "\n"


def _second_effect_lines(report: dict) -> list:
    """The second step: each pair tried beside the first cause, and what it gained."""
    step = report.get("second_effect")
    if not step:
        return []
    head = ["## Second effect", ""]
    if not step["tried"]:
        return head + [f"Not tried: {step['why']}.", ""]
    rows = [[" + ".join(o["effects"]), _params(o["parameters"]), _num(o["E_um"]),
             f"{o['delta_bic']:.1f}", f"{o['delta_bic_vs_added_alone']:.1f}",
             f"{'yes' if o['systematic_misfit'] else 'no'} ({o['misfit_p_value']:.2g})",
             "**added**" if step["added"] is o or (step["added"] or {}).get("model") == o["model"]
             else ""] for o in sorted(step["options"], key=lambda o: o["bic"])]
    return head + [
        f"From `{step['parent']}` (the lowest-BIC cause that earns its parameter), each pair "
        f"that holds it was fitted. A pair is added if its ΔBIC ≤ "
        f"{report['settings']['delta_bic']:g} against each of its causes alone and its "
        "residuals pass the pattern test.", "",
        markdown_table(rows, ("effects", "parameters (MPa, mm, 1)", "E (µm)",
                              f"ΔBIC vs {step['parent']}", "ΔBIC vs the added alone",
                              "misfit left (p)", ""), align=False), ""]


#: The columns of the candidates' table of ``report.md``.
CANDIDATE_COLUMNS = ("cause", "extra parameter", "E (µm)", "E ratio", "ΔBIC", "misfit left (p)",
                     "holdout E (µm)", "holdout ratio", "verdict")


def _candidate_cells(c: dict, report: dict) -> list:
    """A candidate's row of the table, formatted."""
    x = c["extra_parameter"]
    unit = "" if x["unit"] == "1" else f" {x['unit']}"
    flag = ("chosen" if c["cause"] == report["cause"] else
            "tied with the chosen" if c["cause"] in (report.get("ambiguous_with") or ())
            else "decisive, but misfit left" if c["decisive"] and not c["removes_misfit"]
            else "not decisive" if not c["decisive"]
            else "decisive, higher BIC" if report["cause"] != "none"
            else "decisive, no pattern (pattern gate on)")
    bound = " (at bound)" if x["at_bound"] else ""
    return [f"{c['cause']}", f"{x['symbol']} = {x['value']:.3g}{unit}{bound}",
            f"{c['E_um']:.3g}", _num(c["E_ratio"], ".2f"), f"{c['delta_bic']:.1f}",
            f"{'yes' if c['systematic_misfit'] else 'no'} ({c['misfit_p_value']:.2g})",
            _num(c["holdout_E_um"]), _num(c["holdout_ratio"], ".2f"), flag]


def _geometry_lines(g) -> list:
    if not g:
        return []
    given = set(g.get("given") or [])
    def one(key, name):
        sd = g.get(f"{name}_sd_mm")
        v = g[f"{name}_mm"]
        return (f"{v:g} mm" + (f" ± {sd:g}" if sd else "")
                + (" (given)" if key in given else " (**assumed**, the paper's)"))
    out = [f"- layers: dermis {one('t_d', 'dermis_thickness')}, hypodermis "
           f"{one('t_h', 'hypodermis_thickness')} over a fixed bottom"]
    out += [f"- geometry: {n}" for n in g.get("notes") or []]
    return out


def write_report(report: dict, out_dir, figures: bool = True) -> dict:
    """Write ``report.json``, ``report.md`` and (optionally) the figures into ``out_dir``.

    Each file is written atomically; ``report.json`` is strict JSON
    (:func:`skinsuction.results.write_json`: NaN and infinities are null).

    Parameters
    ----------
    report : dict
        The report of :func:`skinsuction.diagnose.diagnose`.
    out_dir : path-like
        The folder (created).
    figures : bool
        Also draw ``fit``, ``residuals`` and ``gain`` (PNG and PDF).

    Returns
    -------
    dict
        ``{name: path}``: ``json``, ``md`` and ``<figure>_png``, ``<figure>_pdf``.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = {"json": out / "report.json", "md": out / "report.md"}
    figs = {}
    if figures:
        import matplotlib.pyplot as plt

        from skinsuction.figures import save_figure
        from skinsuction.figures.diagnosis import plot_fit, plot_gain, plot_residuals

        for name, fn in (("fit", plot_fit), ("residuals", plot_residuals), ("gain", plot_gain)):
            fig = fn(report)
            png, pdf = out / f"{name}.png", out / f"{name}.pdf"
            save_figure(fig, png, pdf)
            plt.close(fig)
            figs[name] = png
            paths[f"{name}_png"], paths[f"{name}_pdf"] = png, pdf
    write_json(paths["json"], report, indent=1, ensure_ascii=False)
    write_text(paths["md"], report_markdown(report, figs))
    return paths
