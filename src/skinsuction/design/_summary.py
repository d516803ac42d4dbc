"""The designs side by side over the skins, and the one recommended for the question."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from ._box import Question

__all__ = ["summarize", "recommend", "design_markdown"]

PARAMETERS = ("X1d", "X1h")
#: a mode 1 or mode 2 design's spectrum (one Prony term), beside the moduli
SPECTRUM_PARAMETERS = ("g_1", "tau_1")


def _parameters(frame) -> tuple:
    """X1d, X1h, and the spectrum's where some design of ``frame`` predicts it."""
    return PARAMETERS + tuple(p for p in SPECTRUM_PARAMETERS
                              if any(c.startswith(f"{p}_") for c in frame.columns))


def _ceiling(gap) -> np.ndarray:
    from skinsuction.evaluation import attribution_ceiling

    return attribution_ceiling(gap)


def summarize(rows: pd.DataFrame, designs: list, causes=(), quantile: float = 0.9
              ) -> pd.DataFrame:
    """One row per design: precision, bounded fractions, detectability, ceilings.

    ``<P>_median``, ``<P>_quantile``: the median and the ``quantile`` (default the
    90th percentile) over the skins of the relative half-width of P's 95 % interval
    (inf where open or beyond the space);
    ``<P>_bounded``: the fraction of skins with both ends inside the space;
    ``<c>_detectable``: the fraction where cause c is detectable;
    ``<c>_median``: its parameter's median half-width over those;
    ``<c>_ceiling``: its mean attribution ceiling against the nearest of every cause
    the diagnosis weighs;
    ``<c>_vs_<r>_ceiling``: the mean attribution ceiling of c against r over them.
    """
    out = []
    for d in designs:
        g = rows[rows["design"] == d.name]
        r = {"design": d.name, "probes": len(d.probes_mm), "max_mbar": d.max_mbar,
             "given": "+".join(sorted(d.given)), "skins": len(g),
             "beyond_space": float(g["beyond_space"].mean()) if len(g) else math.nan}
        for p in _parameters(rows):
            if p in SPECTRUM_PARAMETERS and d.protocol == "ramp":
                continue  # a ramp does not see the spectrum: not predicted
            w = g[f"{p}_halfwidth"].where(~g["beyond_space"], np.inf).astype(float) \
                if f"{p}_halfwidth" in g else pd.Series(np.inf, index=g.index)
            r[f"{p}_median"] = float(w.median()) if len(w) else math.nan
            r[f"{p}_quantile"] = (float(w.quantile(quantile, interpolation="higher"))
                                  if len(w) else math.nan)
            r[f"{p}_bounded"] = float(np.isfinite(w).mean()) if len(w) else math.nan
        for c in causes:
            det = g.get(f"{c}_detectable")
            if det is None or det.isna().all():
                r[f"{c}_detectable"] = math.nan
                continue
            on = g[det.fillna(False).astype(bool)]
            r[f"{c}_detectable"] = float(det.fillna(False).astype(bool).mean())
            r[f"{c}_median"] = float(on[f"{c}_halfwidth"].median()) if len(on) else math.nan
            # against the nearest of every cause the diagnosis weighs: the bound on
            # naming it at all
            gaps = on[[col for col in on if col.startswith(f"{c}_vs_") and col.endswith("_gap")]]
            r[f"{c}_ceiling"] = (float(_ceiling(gaps.min(axis=1).astype(float)).mean())
                                 if len(on) and gaps.shape[1] else math.nan)
            for rival in causes:
                col = f"{c}_vs_{rival}_gap"
                if rival != c and col in on:
                    r[f"{c}_vs_{rival}_ceiling"] = (float(_ceiling(on[col]).mean())
                                                    if len(on) else math.nan)
        out.append(r)
    return pd.DataFrame(out)


def _shortfalls(row, question: Question) -> list:
    """For each criterion of the question, how far the design is from it (<= 0: met)."""
    out = []
    for p, target in question.precision.items():
        w = row.get(f"{p}_quantile", math.nan)
        if p not in PARAMETERS + SPECTRUM_PARAMETERS:  # a cause's: its median where detectable
            w = row.get(f"{p}_median", math.nan)
        short = (w / target - 1.0) if np.isfinite(w) else math.inf
        out.append((f"{p} ±{100 * target:g} %", short))
    for a in question.tell:
        for b in question.tell:
            if a == b:
                continue
            c = row.get(f"{a}_vs_{b}_ceiling", math.nan)
            det = row.get(f"{a}_detectable", math.nan)
            short = math.inf if not (det > 0) or not np.isfinite(c) else question.rate - c
            out.append((f"{a} vs {b} >= {100 * question.rate:g} %", short))
    if len(question.tell) == 1:
        det = row.get(f"{question.tell[0]}_detectable", math.nan)
        out.append((f"{question.tell[0]} detectable", math.inf if not det > 0 else 1.0 - det))
    return out


def recommend(summary: pd.DataFrame, question: Question) -> dict:
    """The design for the question: the fewest probes, then the lowest suction, then
    the fewest thicknesses given, among those that meet every criterion.

    Returns
    -------
    dict
        ``met`` (bool), ``design`` (the recommended one, or the best offered when
        none meets it: the most criteria met, then the smallest worst shortfall),
        ``criteria`` (name -> shortfall, <= 0 met) and ``meeting`` (every design
        that meets it).
    """
    scored = []
    for _, row in summary.iterrows():
        crit = _shortfalls(row, question)
        met = sum(s <= 0 for _, s in crit)
        worst = max((s for _, s in crit), default=-math.inf)
        scored.append((row["design"], crit, met, worst, row["probes"], row["max_mbar"],
                       len(row["given"].split("+")) if row["given"] else 0))
    meeting = [s for s in scored if s[2] == len(s[1])]
    if meeting:
        best = min(meeting, key=lambda s: (s[4], s[5], s[6], s[3]))
    else:
        best = min(scored, key=lambda s: (-s[2], s[3], s[4], s[5]))
    return {"met": bool(meeting), "design": best[0], "criteria": dict(best[1]),
            "meeting": [s[0] for s in meeting]}


def _fmt(w) -> str:
    if w is None or (isinstance(w, float) and math.isnan(w)):
        return "–"
    return "open" if not np.isfinite(w) else f"±{100 * w:.3g} %"


def design_markdown(summary: pd.DataFrame, question: Question, choice: dict, causes=(),
                    notes=(), header: str = "") -> str:
    """The table of designs and the recommendation, in Markdown."""
    lines = ["# Measurement design", "", header, "", f"**Question:** {question.text}.", ""]
    if choice["met"]:
        lines.append(f"**Recommended: {choice['design']}** (the fewest probes, then the lowest "
                     f"suction, that meet the question; {len(choice['meeting'])} of "
                     f"{len(summary)} designs meet it).")
    else:
        lines.append(f"**No design meets the question.** The best offered: "
                     f"**{choice['design']}**; what it misses:")
    def status(s):
        return "met" if s <= 0 else ("not reached" if not np.isfinite(s) else f"short by {s:.3g}")

    lines += [""] + [f"- {k}: {status(s)}" for k, s in choice["criteria"].items()] + [""]
    pct = f"{100 * question.quantile:g}th pct"
    params = _parameters(summary)
    head = ["design", "beyond the space"] + [f"{p}: median, {pct}, bounded" for p in params]
    head += [f"{c}: detectable, ceiling (nearest rival)" for c in causes]
    pairs = [(a, b) for a in causes for b in causes if a != b]
    head += [f"ceiling {a} vs {b}" for a, b in pairs]
    lines += ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for _, r in summary.iterrows():
        cells = [r["design"], f"{100 * r['beyond_space']:.0f} %"]
        cells += ["–" if not np.isfinite(r.get(f"{p}_bounded", math.nan))
                  else f"{_fmt(r[f'{p}_median'])}, {_fmt(r[f'{p}_quantile'])}, "
                  f"{100 * r[f'{p}_bounded']:.0f} %" for p in params]
        cells += ["–" if not np.isfinite(r.get(f"{c}_detectable", math.nan))
                  else f"{100 * r[f'{c}_detectable']:.0f} %, "
                  + ("–" if not np.isfinite(r.get(f"{c}_ceiling", math.nan))
                     else f"{100 * r[f'{c}_ceiling']:.0f} %") for c in causes]
        cells += [("–" if not np.isfinite(r.get(f"{a}_vs_{b}_ceiling", math.nan))
                   else f"{100 * r[f'{a}_vs_{b}_ceiling']:.0f} %") for a, b in pairs]
        lines.append("| " + " | ".join(cells) + " |")
    lines += ["", "Half-widths: of the 95 % profile-likelihood interval, relative to the "
              "value (lambda0: to its strain, lambda0 - 1), on the noise-free curves with "
              "the design's sd per point; open: an end at the space's edge. Ceiling: the "
              "mean of Phi(sqrt(g)/2) over the skins where the cause is detectable, g the "
              "chi^2 gap of the rival's best fit; no diagnosis that sees only the curves "
              "names the cause more often."]
    if notes:
        lines += ["", "## Notes", ""] + [f"- {n}" for n in notes]
    return "\n".join(lines) + "\n"

