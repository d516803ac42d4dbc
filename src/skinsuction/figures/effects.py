"""Single and paired effects in time curves or ramps: how often each is named.

One panel per design: for each effect, the fraction of the draws where it is
detectable that name it (dark) and that name it or tie it (light), with the counts;
the draws with a wrong effect not tied and the elastic draws with a false effect as
the last two bars (the summary of :func:`skinsuction.evaluation.effects_confusion_summary`
or :func:`skinsuction.evaluation.ramp_effects_summary`).
"""

from __future__ import annotations

import numpy as np

from ._style import WIDTH_IN, plt, save, style

__all__ = ["plot_effects_confusion"]


def plot_effects_confusion(summary: dict, *paths):
    """Draw the study's rates.

    Parameters
    ----------
    summary : dict
        :func:`skinsuction.evaluation.effects_confusion_summary` of the study's rows.
    *paths : path-like
        Where to save the figure.

    Returns
    -------
    matplotlib.figure.Figure
    """
    summary = {k: v for k, v in summary.items() if k != "failed"}
    with style():
        fig, axes = plt.subplots(1, max(len(summary), 1), figsize=(WIDTH_IN, 0.42 * WIDTH_IN),
                                 constrained_layout=True, squeeze=False, sharey=True)
        for k, (ax, (design, rec)) in enumerate(zip(axes[0], summary.items())):
            labels, named, tied, counts = [], [], [], []
            for e, v in rec["effects"].items():
                n = max(v["detectable"], 1)
                labels.append(e.replace("viscoelastic_", "").replace("strain_", ""))
                named.append(v["named"] / n)
                tied.append(v["right_or_tied"] / n)
                counts.append(f"{v['named']}/{v['detectable']}")
            for name, (a, b) in (("wrong, not tied", rec["wrong_not_tied"]),
                                 ("false (elastic)", rec["false_effect"])):
                labels.append(name)
                named.append(a / max(b, 1))
                tied.append(a / max(b, 1))
                counts.append(f"{a}/{b}")
            x = np.arange(len(labels))
            ax.bar(x, tied, color="tab:blue", alpha=0.35, label="named or tied")
            ax.bar(x, named, color="tab:blue", label="named")
            for xi, (h, c) in enumerate(zip(tied, counts)):
                ax.text(xi, min(h, 1.0) + 0.02, c, ha="center", va="bottom", fontsize=7)
            ax.axhline(0.9, color="0.5", lw=0.6, ls="--")
            ax.set_xticks(x, labels, rotation=30, ha="right")
            ax.set_ylim(0, 1.15)
            ax.set_title(f"({chr(97 + k)}) {design}")
        axes[0, 0].set_ylabel("fraction of the detectable draws")
        axes[0, 0].legend(loc="upper right", fontsize=7)
        save(fig, *paths)
    return fig
