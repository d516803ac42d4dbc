"""The verdict of a diagnosis in plain sentences: the ``summary`` of its report."""

from __future__ import annotations

from skinsuction.space import NONE

from ._rule import BEYOND_SPACE

__all__ = ["summary_text"]


def _params_text(params):
    out = []
    for k, v in params.items():
        unit = {"X1d": "MPa", "X1h": "MPa", "X2d": "MPa", "X2h": "MPa", "t_d": "mm"}.get(k, "")
        out.append(f"{k} = {v:.3g}{' ' + unit if unit else ''}")
    return ", ".join(out)


def _beyond_text(report: dict) -> str:
    parts = []
    for f in report.get("beyond_space") or []:
        where = ("the end of the simulated window" if f["edge"] == "window"
                 else "the coverage frontier, where the FE rays stop")
        parts.append(f"{f['parameter']} = {f['value']:.3g} of the {f['model']} fit is at the "
                     f"{f['side']} edge ({where}); widen {f['config_key']}")
    return ("BEYOND THE SIMULATED SPACE: " + "; ".join(parts) + ". The values at the edge are "
            "bounds, not estimates. ") if parts else ""


def summary_text(report: dict) -> str:
    """The verdict in two or three plain sentences (``report["summary"]``).

    Parameters
    ----------
    report : dict
        The report of :func:`skinsuction.diagnose.diagnose` (its ``summary`` need
        not be set).

    Returns
    -------
    str
        The neo-Hookean fit, the assumptions, any edge of the space, the cause (or
        why none) with its gain and ties, and the causes a ramp cannot test.
    """
    s = _summary_text(report)
    for u in report.get("untestable") or ():
        s += f" Not tested: {u['cause']} ({u['reason'].split(':')[0]})."
    return s


def _summary_text(report: dict) -> str:
    b = report["baseline"]
    s = (f"Neo-Hookean fit: {_params_text(b['parameters'])}, E = {b['E_um']:.3g} µm "
         f"(noise {report['noise_um']:.2g} µm per point, {report['noise']['method']}). ")
    g = report.get("geometry") or {}
    if g.get("assumptions"):
        s += "ASSUMED: " + "; ".join(g["assumptions"]) + ". "
    s += _beyond_text(report)
    if report["cause"] == BEYOND_SPACE:
        return s + "No cause can be named until the space covers the fit."
    if report["cause"] == NONE or report["cause"] not in {
            c["cause"] for c in report["candidates"]}:
        if report["verdict"] == "unexplained_misfit":
            s += ("The neo-Hookean model misses a systematic pattern, but no candidate cause "
                  "removes it while earning its extra parameter: cause none "
                  "(misfit unexplained by the causes tried).")
        else:
            s += ("The residuals are consistent with the noise; no candidate earns its extra "
                  "parameter: cause none.")
        return s
    step = report.get("second_effect") or {}
    if step.get("added"):
        return s + _pair_text(report, step)
    c = next(c for c in report["candidates"] if c["cause"] == report["cause"])
    g = report["gain"]
    if g is None:  # the lowest BIC, at an edge, without earning its parameter
        return s + (f"Best candidate: {c['cause']} (delta BIC {c['delta_bic']:.1f}), at the "
                    "edge of the space: no cause named.")
    hyp = f" ({c['hypothesis']})" if c.get("hypothesis") else ""
    s += (f"Cause: {c['cause']}{hyp}. Extended fit: "
          f"{_params_text(c['parameters'])}, E = {c['E_um']:.3g} µm "
          f"(E ratio {g['E_ratio']:.2f}, delta BIC {g['delta_bic']:.1f}")
    if g["holdout_ratio"] is not None:
        s += f", cross-probe holdout E ratio {g['holdout_ratio']:.2f}"
    s += "); its residuals are consistent with the noise."
    if not b["systematic_misfit"]:
        s += (" The neo-Hookean residuals alone show no smooth pattern at level "
              f"{report['settings']['alpha']:g}: the effect is near the noise, found by the "
              "cause's own fit.")
    if report.get("ambiguous_with"):
        others = ", ".join(report["ambiguous_with"])
        s += (f" {others} explains both curves almost as well (BIC within "
              f"{report['settings']['ambiguity_bic']:g})")
        s += ". Treat them as hard to separate; " + _tie_breaker_text(
            [c["cause"], *report["ambiguous_with"]])
    elif report.get("runner_up"):
        r = report["runner_up"]
        s += f" Next best: {r['cause']} (BIC {r['bic_above_chosen']:.1f} higher)."
    tried = [o for o in step.get("options") or () if not (o["decisive"] and o["removes_misfit"])]
    if tried:
        o = min(tried, key=lambda o: o["bic"])
        s += (f" A second effect was tried: {o['added']} beside {step['parent']} "
              f"(delta BIC {o['delta_bic']:.1f}) does not earn its place.")
    return s


def _pair_text(report: dict, step: dict) -> str:
    """Two effects: the first cause, the second added to it, their fit and gains."""
    o, g = step["added"], report["gain"]
    first, second = o["effects"]
    s = (f"Two effects: {first}, then {second} added to it. Fit with both: "
         f"{_params_text(o['parameters'])}, E = {o['E_um']:.3g} µm (delta BIC "
         f"{g['delta_bic']:.1f} against neo-Hookean, {o['delta_bic']:.1f} against {first} "
         f"alone, {o['delta_bic_vs_added_alone']:.1f} against {second} alone); its residuals "
         "are consistent with the noise.")
    if report.get("ambiguous_with"):
        s += (f" {', '.join(report['ambiguous_with'])} explains the curves almost as well "
              f"(BIC within {report['settings']['ambiguity_bic']:g}).")
    return s


def _tie_breaker_text(causes) -> str:
    """What would decide between tied causes: a thickness among them, measured on the
    site, is what the curves cannot tell (docs/diagnosis.md, "With the subject's layers")."""
    from skinsuction.measured import GEOMETRY_KEYS

    keys = [f"{c}_mm" for c in causes if f"{c}_mm" in GEOMETRY_KEYS]
    if not keys:
        return "an independent measurement of one of them would decide."
    what = " and ".join("the " + k.removesuffix("_mm").replace("_", " ") for k in keys)
    how = "; ".join(f"'# {k}:' header line or --{k.replace('_', '-')}" for k in keys)
    return (f"{what}, measured on the site (ultrasound, OCT), would decide: give "
            f"{'it' if len(keys) == 1 else 'them'} ({how}).")
