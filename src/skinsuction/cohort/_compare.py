"""Group comparison of a study: paired within groups, between groups against a reference.

With ``subject`` and ``visit`` columns the design is paired: the change of
log X1d between the first two visits of each subject.  Within each group,
the Wilcoxon signed-rank test (two-sided) tests a zero median change; its
effect size is the median change in % with a bootstrap 95 % interval
(seeded) and the matched-pairs rank-biserial correlation.  Between groups,
the Mann-Whitney U test compares the changes of each group with those of
the reference group (rank-biserial effect size).  Why rank tests: moduli
are skewed and a misfitting curve can give an outlier, and with one pair
per subject the paired test removes the inter-subject spread (40-70 % in
X1d) as a mixed model with a random intercept would, without assuming
normal residuals.  Without visits, groups are compared by Mann-Whitney on
log X1d.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["compare_groups"]


def _bootstrap_median(x, rng, n=10000):
    x = np.asarray(x, dtype=float)
    idx = rng.integers(0, x.size, size=(n, x.size))
    meds = np.median(x[idx], axis=1)
    return np.percentile(meds, [2.5, 97.5])


def _rank_biserial_paired(d):
    from scipy.stats import rankdata

    d = np.asarray(d, dtype=float)
    d = d[d != 0]
    if d.size == 0:
        return 0.0
    r = rankdata(np.abs(d))
    return float((r[d > 0].sum() - r[d < 0].sum()) / r.sum())


def _rank_biserial(u, n1, n2) -> float:
    """Rank-biserial correlation of a Mann-Whitney U of the first sample (+1: it is larger)."""
    return float(2.0 * u / (n1 * n2) - 1.0)


def compare_groups(df, parameter: str = "x1d_mpa", *, reference=None, seed: int = 0):
    """The group comparison of a study (method in the module docstring).

    Returns ``(rows, notes)``: one dict per test with ``group``, ``test``,
    ``n``, ``median_change_percent`` (or medians), its bootstrap interval,
    ``statistic``, ``p_value``, ``effect_size`` (rank-biserial), and text notes
    (excluded measurements, the design used).  A study that mixes ramps and time
    curves (a ``protocol`` column: "mode 1", "mode 2", empty for a ramp) is
    compared protocol by protocol, each row saying which: a time curve's X1d is
    a long-time modulus and a ramp's a quasi-static one, and one subject's two
    measurements are not independent.
    """
    if "protocol" not in df.columns:
        return _compare(df, parameter, reference=reference, seed=seed)
    kind = df["protocol"].fillna("ramp").astype(str).replace("", "ramp")
    if kind.nunique() < 2:
        return _compare(df, parameter, reference=reference, seed=seed)
    rows, notes = [], [f"ramps and time curves compared apart ({', '.join(sorted(kind.unique()))})"]
    for k in sorted(kind.unique()):
        r, n = _compare(df[kind == k], parameter, reference=reference, seed=seed)
        rows += [{"protocol": k, **row} for row in r]
        notes += [f"{k}: {note}" for note in n]
    return rows, notes


def _compare(df, parameter: str, *, reference=None, seed: int = 0):
    """:func:`compare_groups` of measurements of one protocol."""
    from scipy import stats

    rng = np.random.default_rng(seed)
    ok = df[df[parameter].notna() & (df[parameter] > 0)].copy()
    notes = []
    n_bad = int(len(df) - len(ok))
    if n_bad:
        notes.append(f"{n_bad} measurement(s) without an estimate (errors) are left out")
    group_col = "group" if "group" in ok.columns else None
    if group_col is None:
        ok["group"] = "all"
        group_col = "group"
    groups = sorted(ok[group_col].astype(str).unique())
    ref = reference if reference in groups else ("control" if "control" in groups else groups[0])
    ok["log_value"] = np.log(ok[parameter].astype(float))
    rows = []
    paired = {"subject", "visit"} <= set(ok.columns)
    if paired:
        visits = sorted(ok["visit"].astype(str).unique(), key=lambda v: (len(v), v))
        if len(visits) < 2:
            paired = False
    if paired:
        v1, v2 = visits[:2]
        notes.append(f"paired design: change of log {parameter} from visit {v1} to visit {v2} "
                     "per subject")
        changes = {}
        for g in groups:
            sub = ok[ok[group_col].astype(str) == g]
            wide = sub.pivot_table(index="subject", columns=sub["visit"].astype(str),
                                   values="log_value", aggfunc="mean")
            complete = wide.dropna(subset=[c for c in (v1, v2) if c in wide.columns]) \
                if {v1, v2} <= set(wide.columns) else wide.iloc[0:0]
            dropped = len(wide) - len(complete)
            if dropped:
                notes.append(f"group {g}: {dropped} subject(s) without both visits are left out")
            d = (complete[v2] - complete[v1]).to_numpy() if len(complete) else np.array([])
            changes[g] = d
            if d.size < 2:
                rows.append({"group": g, "test": "Wilcoxon signed-rank (paired)", "n": int(d.size),
                             "p_value": None})
                continue
            w = stats.wilcoxon(d, alternative="two-sided")
            lo, hi = _bootstrap_median(d, rng)
            rows.append({"group": g, "comparison": f"visit {v2} vs {v1}",
                         "test": "Wilcoxon signed-rank (paired, two-sided)", "n": int(d.size),
                         "median_change_percent": 100 * (math.exp(float(np.median(d))) - 1),
                         "ci_low_percent": 100 * (math.exp(lo) - 1),
                         "ci_high_percent": 100 * (math.exp(hi) - 1),
                         "statistic": float(w.statistic), "p_value": float(w.pvalue),
                         "effect_size": _rank_biserial_paired(d),
                         "effect_size_name": "matched-pairs rank-biserial"})
        for g in groups:
            if g == ref or changes[g].size < 2 or changes[ref].size < 2:
                continue
            u = stats.mannwhitneyu(changes[g], changes[ref], alternative="two-sided")
            diff = np.median(changes[g]) - np.median(changes[ref])
            boot = [np.median(rng.choice(changes[g], changes[g].size))
                    - np.median(rng.choice(changes[ref], changes[ref].size)) for _ in range(4000)]
            lo, hi = np.percentile(boot, [2.5, 97.5])
            rows.append({"group": f"{g} vs {ref}", "comparison": f"change {v1} -> {v2}",
                         "test": "Mann-Whitney U (two-sided) on the paired changes",
                         "n": int(changes[g].size + changes[ref].size),
                         "median_change_percent": 100 * (math.exp(diff) - 1),
                         "ci_low_percent": 100 * (math.exp(lo) - 1),
                         "ci_high_percent": 100 * (math.exp(hi) - 1),
                         "statistic": float(u.statistic), "p_value": float(u.pvalue),
                         "effect_size": _rank_biserial(u.statistic, changes[g].size,
                                                       changes[ref].size),
                         "effect_size_name": "rank-biserial"})
    else:
        notes.append(f"unpaired design: log {parameter} compared between groups")
        rows += _unpaired(ok, groups, ref, group_col, parameter, rng)
    return rows, notes


def _unpaired(ok, groups, ref, group_col, parameter, rng) -> list:
    """Mann-Whitney U on log ``parameter`` of each group against ``ref``, with the
    difference of the medians and its seeded bootstrap 95 % interval."""
    from scipy import stats

    rows = []
    base = ok[ok[group_col].astype(str) == ref]["log_value"].to_numpy()
    for g in groups:
        if g == ref:
            continue
        x = ok[ok[group_col].astype(str) == g]["log_value"].to_numpy()
        if x.size < 2 or base.size < 2:
            continue
        u = stats.mannwhitneyu(x, base, alternative="two-sided")
        boot = [np.median(rng.choice(x, x.size)) - np.median(rng.choice(base, base.size))
                for _ in range(4000)]
        lo, hi = np.percentile(boot, [2.5, 97.5])
        rows.append({"group": f"{g} vs {ref}", "comparison": parameter,
                     "test": "Mann-Whitney U (two-sided)", "n": int(x.size + base.size),
                     "median_change_percent": 100 * (math.exp(np.median(x)
                                                              - np.median(base)) - 1),
                     "ci_low_percent": 100 * (math.exp(lo) - 1),
                     "ci_high_percent": 100 * (math.exp(hi) - 1),
                     "statistic": float(u.statistic), "p_value": float(u.pvalue),
                     "effect_size": _rank_biserial(u.statistic, x.size, base.size),
                     "effect_size_name": "rank-biserial"})
    return rows
