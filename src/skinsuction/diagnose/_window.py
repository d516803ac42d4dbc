"""The causes' X1h/X1d window: where their rays are solved when solved on demand.

A probe or layers that the precomputed space lacks get their rays solved on demand;
a cause's rays are then solved only within ``cause_window_decades`` of the
neo-Hookean fit (:func:`ratio_window`), and the window widens where a cause's fit
reaches its outer cell (:func:`fit_in_window`, :func:`widened_window`).
"""

from __future__ import annotations

import math

from skinsuction.space import BASELINE

__all__ = ["ratio_window", "widened_window", "fit_in_window"]


def ratio_window(theta, decades: float) -> tuple:
    """X1h/X1d within ``decades`` of a fit.

    Parameters
    ----------
    theta : array_like
        The fit's coordinates ``(log10 X1d, log10 X1h/X1d, ...)``.
    decades : float
        Half-width of the window (decades of X1h/X1d).

    Returns
    -------
    tuple of float
        ``(lower, upper)`` X1h/X1d.

    Examples
    --------
    >>> ratio_window([-1.5, -2.0], 1.0)
    (0.001, 0.1)
    """
    r, half = 10.0 ** float(theta[1]), 10.0 ** float(decades)
    return (r / half, r * half)


def widened_window(nodes, ratio: float, full, decades: float):
    """The wider window when ``ratio`` lies in an outer cell of the cut ``nodes``.

    Widened by as many of the ``full`` nodes as ``decades`` spans (at least one) on
    that side.

    Parameters
    ----------
    nodes : sequence of float
        The X1h/X1d nodes of the cut window (a contiguous run of ``full``).
    ratio : float
        X1h/X1d of the fit.
    full : sequence of float
        Every X1h/X1d node of the space, ascending.
    decades : float
        How far a widening reaches (decades).

    Returns
    -------
    tuple of float or None
        ``(lower, upper)`` X1h/X1d of the wider window; None when ``ratio`` is
        inside, or the cut already reaches that end.

    Examples
    --------
    >>> full = (1e-4, 1e-3, 1e-2, 0.1, 1.0)
    >>> widened_window((1e-3, 1e-2, 0.1), 2e-3, full, 1.0)
    (0.0001, 0.1)
    >>> widened_window((1e-3, 1e-2, 0.1), 5e-2, full, 1.0)
    (0.001, 1.0)
    >>> widened_window((1e-4, 1e-3, 1e-2), 5e-4, full, 1.0) is None
    True
    """
    full = tuple(full)
    per_decade = (len(full) - 1) / math.log10(full[-1] / full[0])
    step = max(1, round(decades * per_decade))
    i0, i1 = full.index(nodes[0]), full.index(nodes[-1])
    if ratio < nodes[1] and i0 > 0:
        i0 = max(0, i0 - step)
    if ratio > nodes[-2] and i1 < len(full) - 1:
        i1 = min(len(full) - 1, i1 + step)
    return None if (i0, i1) == (full.index(nodes[0]), full.index(nodes[-1])) else (full[i0],
                                                                                   full[i1])


def fit_in_window(space, fit, full, decades: float, rebuild, refit):
    """A cause's fit on a cut X1h/X1d window, widened and refitted until it lies inside.

    Parameters
    ----------
    space : RaySpace
        The cause's space over the cut window.
    fit : Fit
        Its fit on that space.
    full : sequence of float
        Every X1h/X1d node of the space.
    decades : float
        How far a widening reaches (decades).
    rebuild : callable
        ``rebuild(window) -> (space, notes)``: the cause's space over a wider window.
    refit : callable
        ``refit(space, previous_fit) -> fit``: the fit on it.

    Returns
    -------
    tuple
        ``(space, fit, notes)``: the last space and its fit, and a note per
        widening.  A space with every node is returned as it is.
    """
    notes = []
    while True:
        r = 10.0 ** float(fit.theta[1])
        window = widened_window(space.spec.ratio_nodes, r, full, decades)
        if window is None:
            return space, fit, notes
        name = space.cause.name if space.cause is not None else BASELINE
        space, more = rebuild(window)
        notes += [f"{name}: its fit reached X1h/X1d = {r:.3g}, in the outer cell of its "
                  f"window: widened to {window[0]:.3g}-{window[1]:.3g}", *more]
        fit = refit(space, fit)
