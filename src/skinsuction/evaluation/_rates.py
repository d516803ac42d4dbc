"""Confusion matrices and rates over the diagnosed draws of :mod:`._confusion`.

Every draw (one row of :func:`~skinsuction.evaluation.run_draw`) records the verdict of
the diagnosis, whether its effect was detectable and whether another cause could
mimic it; :func:`summarise` turns the rows into confusion matrices (all and
detectable draws) and rates per true cause, :func:`under_rule` reads the rows as
the rule with or without its pattern gate would have them, and
:func:`attribution_ceiling` is the most a decision on the curves could name right.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from skinsuction.space import NONE

__all__ = ["UNDIAGNOSED", "under_rule", "summarise", "attribution_ceiling", "wrong_untied",
           "interval_coverage"]


#: Draws without a diagnosis: the FE run stopped, the loader refused its curve, or
#: the other solver cannot carry the skin (:data:`~skinsuction.evaluation.OTHER_SOLVERS`).
UNDIAGNOSED = ("fe_failed", "input_rejected", "solver_refused")


def under_rule(rows: pd.DataFrame, pattern_gate: bool) -> pd.DataFrame:
    """The rows as the rule with or without the pattern gate would have them: its
    ``named``, ``verdict``, ``ambiguous_with`` and ``detectable`` (each draw records
    both rules' verdicts on the same fits, so one run compares them)."""
    tag = "gated" if pattern_gate else "ungated"
    out = rows.copy()
    for col in ("named", "verdict", "ambiguous_with", "detectable"):
        alt = f"{col}_{tag}"
        if alt in out:
            undiagnosed = out["named"].isin(UNDIAGNOSED) | out[alt].isna()
            out[col] = out[alt].where(~undiagnosed, out[col])
    return out


def summarise(rows: pd.DataFrame, causes) -> dict:
    """Confusion matrices (all and detectable draws), rates and parameter errors."""
    labels = [NONE, *causes]
    rows = rows.copy()
    for col in ("base_x1d", "ext_x1d", "ext_value", "value", "detectable", "verdict"):
        if col not in rows:
            rows[col] = np.nan
    ok = rows[~rows["named"].isin(UNDIAGNOSED)].copy()
    ok["detectable"] = ok["detectable"].fillna(True).astype(bool)
    det = ok[(ok["truth"] == NONE) | ok["detectable"]]
    cols = labels + sorted(set(ok["named"]) - set(labels))

    def matrix(frame):
        return pd.crosstab(frame["truth"], frame["named"]).reindex(
            index=labels, columns=cols, fill_value=0)

    out = {"all": matrix(ok), "detectable": matrix(det)}
    rates = []
    for truth in labels:
        g_all = ok[ok["truth"] == truth]
        g = det[det["truth"] == truth]
        r = {"truth": truth, "draws": len(g_all), "fe_failed":
             int(((rows["truth"] == truth) & (rows["named"] == "fe_failed")).sum()),
             "input_rejected":
             int(((rows["truth"] == truth) & (rows["named"] == "input_rejected")).sum()),
             "detectable": len(g) if truth != NONE else len(g_all),
             "detectable_fraction": (len(g) / len(g_all)) if len(g_all) and truth != NONE
             else math.nan,
             "named_right": float((g["named"] == truth).mean()) if len(g) else math.nan,
             **_distinguishable_rates(g, truth),
             "beyond_space": float((g["verdict"] == "beyond_space").mean()) if len(g) else
             math.nan,
             "wrong_untied": float(wrong_untied(g_all, truth).mean()) if len(g_all)
             and truth != NONE else math.nan}
        hit = g[g["named"] == truth]
        if truth == NONE:
            r["false_alarm"] = float((g["named"] != NONE).mean()) if len(g) else math.nan
            r["x1d_error_median"] = float((hit["base_x1d"] / hit["x1d"] - 1).abs().median())
        elif len(hit):
            r["x1d_error_median"] = float((hit["ext_x1d"] / hit["x1d"] - 1).abs().median())
            if truth == "pre_tension":
                r["extra_error_median"] = float(((hit["ext_value"] - 1) / (hit["value"] - 1)
                                                 - 1).abs().median())
            else:
                r["extra_error_median"] = float((hit["ext_value"] / hit["value"] - 1)
                                                .abs().median())
        rates.append(r)
    out["rates"] = pd.DataFrame(rates)
    return out


def attribution_ceiling(rival_gap) -> np.ndarray:
    """Chance that an ideal decision names the true cause over its nearest rival.

    With noise, the chi^2 gap ``g`` between the best rival and the true cause on
    the noise-free curves becomes ``g + 2 sqrt(g) z`` (z standard normal) when the two
    models nearly span the same curves, as causes that mimic each other do; the
    truth wins with probability ``Phi(sqrt(g) / 2)``: 0.5 at g = 0, 0.84 at g = 4,
    0.89 at the tie rule's 6.  A negative gap (the rival fits the truth's noise-free
    curves better than the true cause's own space does) gives ``Phi(-sqrt(-g) / 2)``.
    Its mean over the detectable draws bounds the rate of any decision that sees
    only the curves (every detection granted).

    Examples
    --------
    >>> attribution_ceiling([0.0, 4.0, -4.0, np.inf]).round(3)
    array([0.5  , 0.841, 0.159, 1.   ])
    """
    from scipy.stats import norm

    g = np.asarray(rival_gap, dtype=float)
    return norm.cdf(np.sign(g) * np.sqrt(np.abs(g)) / 2)


def _distinguishable_rates(g, truth) -> dict:
    """Over the detectable draws that the other causes cannot mimic (``rival_gap``):
    how many, and the fraction named right; empty without the column."""
    if truth == NONE or "distinguishable" not in g:
        return {}
    d = g[g["distinguishable"].fillna(True).astype(bool)]
    tied = (g["ambiguous_with"] if "ambiguous_with" in g else pd.Series("", index=g.index))
    tied = tied.fillna("").astype(str).str.split(";").apply(lambda a: truth in a)
    return {"distinguishable": len(d),
            "named_right_distinguishable": float((d["named"] == truth).mean()) if len(d)
            else math.nan,
            "right_or_tied": float(((g["named"] == truth) | tied).mean()) if len(g)
            else math.nan,
            # the mean chance of an ideal decision: what the curves allow at most
            "ceiling_named_right": float(attribution_ceiling(
                g["rival_gap"].fillna(np.inf)).mean())
            if len(g) and "rival_gap" in g else math.nan}


def _tied_with(g, truth) -> pd.Series:
    tied = (g["ambiguous_with"] if "ambiguous_with" in g else pd.Series("", index=g.index))
    return tied.fillna("").astype(str).str.split(";").apply(lambda a: truth in a)


def wrong_untied(rows: pd.DataFrame, truth: str) -> pd.Series:
    """Per draw of ``truth``: named another cause, and not tied with the truth (a
    confident wrong cause; ``none``, an undiagnosed draw and a verdict of
    ``beyond_space``, which says that the fit stands at the space's edge, are not).

    Examples
    --------
    >>> rows = pd.DataFrame({"named": ["pre_tension", "hypodermis_thickness", "none",
    ...                                "hypodermis_thickness", "dermis_thickness"],
    ...                      "ambiguous_with": ["", "pre_tension", "", "", ""],
    ...                      "verdict": ["cause_found"] * 4 + ["beyond_space"]})
    >>> wrong_untied(rows, "pre_tension").tolist()
    [False, False, False, True, False]
    """
    named = rows["named"].astype(str)
    verdict = (rows["verdict"] if "verdict" in rows else pd.Series("", index=rows.index))
    other = (named != truth) & (named != NONE) & ~named.isin(UNDIAGNOSED) \
        & (named != "beyond_space") & (verdict.astype(str) != "beyond_space")
    return other & ~_tied_with(rows, truth)


def interval_coverage(rows: pd.DataFrame) -> pd.DataFrame:
    """How often the 95 % intervals of the standing model cover the truth.

    Over the draws whose cause was named right (``none`` for the neo-Hookean draws):
    X1d, X1h and the cause's parameter (the ``ci_*`` columns of
    :func:`~skinsuction.evaluation.run_draw`); an interval open at the space's edge
    covers on that side.

    Returns
    -------
    pandas.DataFrame
        One row per true cause: ``named_right`` draws, and per parameter the number
        of intervals and the fraction covering.
    """
    out = []
    for truth, g in rows[rows["named"] == rows["truth"]].groupby("truth", sort=False):
        r = {"truth": truth, "named_right": len(g)}
        for col, true in (("x1d", g["x1d"]), ("x1h", g["x1h"]), ("value", g.get("value"))):
            lo, hi = g.get(f"ci_{col}_lo"), g.get(f"ci_{col}_hi")
            if lo is None or true is None or truth == NONE and col == "value":
                continue
            has = lo.notna() & hi.notna()
            cover = (lo <= true * (1 + 1e-9)) & (true <= hi * (1 + 1e-9))
            r[f"{col}_intervals"] = int(has.sum())
            r[f"{col}_covered"] = float(cover[has].mean()) if has.any() else math.nan
        out.append(r)
    return pd.DataFrame(out)
