"""Figures of a study (:mod:`skinsuction.cohort`): distributions, paired changes, causes.

Examples
--------
>>> import pandas as pd
>>> df = pd.DataFrame({"subject": ["A", "A", "B", "B"], "visit": ["1", "2", "1", "2"],
...                    "group": ["t", "t", "c", "c"], "x1d_mpa": [0.02, 0.025, 0.03, 0.03],
...                    "x1d_lower_mpa": [0.019, 0.024, 0.029, 0.029],
...                    "x1d_upper_mpa": [0.021, 0.026, 0.031, 0.031],
...                    "cause": ["none", "none", "none", "strain_stiffening"]})
>>> [ax.get_ylabel() for ax in plot_paired(df).axes][:1]
['$X_1^d$ (MPa)']
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from skinsuction.figures import _style

__all__ = ["plot_distributions", "plot_paired", "plot_causes", "write_study_figures"]

GROUP_COLORS = ["#1b6ca8", "#d1495b", "#2e933c", "#edae49", "#6c4f77", "0.4"]


def _plain(minor=False):
    """Tick labels 0.01, 0.02, ... on a log axis (minor ticks: 2, 3, 5 only)."""
    from matplotlib.ticker import FuncFormatter

    def fmt(x, _):
        lead = round(x / 10 ** np.floor(np.log10(x)), 6)
        if minor and lead not in (2, 3, 5):
            return ""
        return f"{x:g}"

    return FuncFormatter(fmt)


def _groups(df):
    return sorted(df["group"].astype(str).unique()) if "group" in df.columns else ["all"]


def _group_col(df):
    return df["group"].astype(str) if "group" in df.columns else np.full(len(df), "all")


def plot_distributions(df, parameter: str = "x1d_mpa", label: str = "$X_1^d$ (MPa)"):
    """Each measurement's estimate with its interval, per group (and visit)."""
    import matplotlib.pyplot as plt

    ok = df[df[parameter].notna()].copy()
    ok["_group"] = _group_col(ok)
    keys = ["_group"] + (["visit"] if "visit" in ok.columns else [])
    cells = list(ok.groupby(keys, sort=True))
    with _style.style():
        fig, ax = plt.subplots(figsize=(_style.WIDTH_IN * 0.6, 3.0))
        groups = _groups(ok) if "group" in ok.columns else ["all"]
        rng = np.random.default_rng(0)  # jitter only
        lo_col, hi_col = parameter.replace("_mpa", "_lower_mpa"), parameter.replace("_mpa", "_upper_mpa")
        for k, (key, g) in enumerate(cells):
            key = key if isinstance(key, tuple) else (key,)
            color = GROUP_COLORS[groups.index(key[0]) % len(GROUP_COLORS)]
            x = k + rng.uniform(-0.18, 0.18, len(g))
            y = g[parameter].astype(float).to_numpy()
            if lo_col in g.columns:
                lo = g[lo_col].astype(float).to_numpy()
                hi = g[hi_col].astype(float).to_numpy()
                ax.vlines(x, lo, hi, color=color, alpha=0.35, linewidth=0.8)
            ax.plot(x, y, "o", markersize=3, color=color)
            ax.hlines(np.median(y), k - 0.3, k + 0.3, color="0.2", linewidth=1.2)
        ax.set_xticks(range(len(cells)))
        ax.set_xticklabels(["\n".join(f"{v}" for v in (key if isinstance(key, tuple) else (key,)))
                            for key, _ in cells], fontsize=7)
        ax.set_yscale("log")
        ax.yaxis.set_major_formatter(_plain())
        ax.yaxis.set_minor_formatter(_plain(minor=True))
        ax.set_ylabel(label)
        ax.set_title("estimates with 95 % intervals; bar: median", fontsize=8)
        fig.tight_layout()
    return fig


def plot_paired(df, parameter: str = "x1d_mpa", label: str = "$X_1^d$ (MPa)"):
    """Before/after per subject (first two visits), one panel per group."""
    import matplotlib.pyplot as plt

    ok = df[df[parameter].notna()].copy()
    ok["_group"] = _group_col(ok)
    visits = sorted(ok["visit"].astype(str).unique(), key=lambda v: (len(v), v))[:2]
    groups = _groups(ok) if "group" in ok.columns else ["all"]
    with _style.style():
        fig, axes = plt.subplots(1, len(groups), figsize=(_style.WIDTH_IN * 0.8, 3.0),
                                 sharey=True, squeeze=False)
        for ax, gname in zip(axes[0], groups):
            g = ok[ok["_group"] == gname]
            color = GROUP_COLORS[groups.index(gname) % len(GROUP_COLORS)]
            wide = g.pivot_table(index="subject", columns=g["visit"].astype(str),
                                 values=parameter, aggfunc="mean")
            for _, r in wide.iterrows():
                y = [r.get(v, np.nan) for v in visits]
                ax.plot(range(len(visits)), y, "-o", color=color, alpha=0.6, markersize=3,
                        linewidth=0.8)
            pairs = wide.dropna(subset=[v for v in visits if v in wide.columns]) \
                if set(visits) <= set(wide.columns) else wide.iloc[0:0]
            if len(pairs) and len(visits) == 2:
                # the median of the per-subject changes, from the median of the first visit
                # (the medians of the two visits are of different subjects)
                change = float(np.median(np.log(pairs[visits[1]] / pairs[visits[0]])))
                start = float(np.median(pairs[visits[0]]))
                ax.plot([0, 1], [start, start * np.exp(change)], "-", color="0.1", linewidth=2)
                ax.text(0.5, 0.97, f"median change {100 * (np.exp(change) - 1):+.1f} %",
                        transform=ax.transAxes, ha="center", va="top", fontsize=7)
            ax.set_xticks(range(len(visits)))
            ax.set_xticklabels([f"visit {v}" for v in visits])
            ax.set_xlim(-0.3, len(visits) - 0.7)
            ax.set_title(f"{gname} ({len(pairs)} pairs)", fontsize=8)
            ax.set_yscale("log")
            ax.yaxis.set_major_formatter(_plain())
            ax.yaxis.set_minor_formatter(_plain(minor=True))
        axes[0][0].set_ylabel(label)
        fig.tight_layout()
    return fig


def plot_causes(df):
    """Share of each named cause of the diagnosis, per group."""
    import matplotlib.pyplot as plt

    ok = df[df["cause"].notna()].copy()
    ok["_group"] = _group_col(ok)
    tab = ok.groupby("_group")["cause"].value_counts(normalize=True).unstack(fill_value=0.0)
    with _style.style():
        fig, ax = plt.subplots(figsize=(_style.WIDTH_IN * 0.55, 2.8))
        bottom = np.zeros(len(tab))
        for k, cause in enumerate(tab.columns):
            ax.bar(range(len(tab)), 100 * tab[cause].to_numpy(), bottom=bottom,
                   color=GROUP_COLORS[k % len(GROUP_COLORS)], label=cause, width=0.6)
            bottom += 100 * tab[cause].to_numpy()
        ax.set_xticks(range(len(tab)))
        ax.set_xticklabels(tab.index)
        ax.set_ylabel("share of measurements (%)")
        ax.legend(fontsize=6, frameon=False, loc="upper left", bbox_to_anchor=(1, 1))
        fig.tight_layout()
    return fig


def _empty(text):
    import matplotlib.pyplot as plt

    with _style.style():
        fig, ax = plt.subplots(figsize=(_style.WIDTH_IN * 0.5, 1.2))
        ax.axis("off")
        ax.text(0.5, 0.5, text, ha="center", va="center", fontsize=8)
    return fig


def write_study_figures(df, out_dir) -> dict:
    """Write the study's figures (PNG and PDF) that its columns allow; returns their paths."""
    import matplotlib.pyplot as plt

    out = Path(out_dir)
    made = {}
    has = df["x1d_mpa"].notna().any()
    todo = [("distribution_x1d", plot_distributions, has, "no measurement was identified"),
            ("paired_x1d", plot_paired, has and {"subject", "visit"} <= set(df.columns),
             "no paired design (the study has no subject and visit columns)"),
            ("causes", plot_causes, df["cause"].notna().any(),
             "no diagnosis (run the study with diagnosis)")]
    for name, fn, possible, why in todo:
        # every figure is written (a workflow output), with the reason where it is empty
        fig = fn(df) if possible else _empty(why)
        png, pdf = out / f"{name}.png", out / f"{name}.pdf"
        _style.save(fig, png, pdf)
        plt.close(fig)
        made[name] = png
    return made
