"""Step 3 with the causes' rays read first: solved only where a cause's fit could matter.

A cause's ray read off its geometry space with an error estimate over the tolerance
is solved by FE (tens of CPU-s a set over a thin dermis).  Most such solves change
nothing: a cause the data do not ask for fits at or near its neutral node, far
from any BIC that could change the verdict.  So each cause is fitted with its rays
as read (:class:`skinsuction.space.DeferredRays`), and fitted again with them
solved only where that fit's delta BIC lies below ``Settings.cause_rays_margin_bic``:
the verdict moves only where a cause's BIC falls below the neo-Hookean one's (the
model it stands on) or by ``delta_bic`` under it (decisive), and a margin above 0
covers what the rays' error can move it (``docs/diagnosis.md``, "A cause's rays read
first").
The refit draws the same seeds as the first fit, so a cause solved is the fit it
was before this step existed.
"""

from __future__ import annotations

import copy
import itertools

from skinsuction.space import BASELINE, DeferredRays

from ._steps import cause_spaces, fit_candidate
from ._window import ratio_window

__all__ = ["fit_candidates"]


def fit_candidates(run, base) -> tuple:
    """Every cause's fit and its gain over the baseline (steps 3a and 3b).

    Parameters
    ----------
    run : Run
    base : Baseline

    Returns
    -------
    tuple
        ``(candidates, fits)``: the candidates as in ``report["candidates"]``, each
        with ``rays_deferred`` (None where no ray of it was read beyond the
        tolerance), and ``{cause: Fit}``.
    """
    strict, margin = run.on_demand, run.settings.cause_rays_margin_bic
    deferring = (DeferredRays.of(strict) if margin is not None and run.windowed
                 else None)
    candidates, fits = [], {}
    if deferring is None:
        for name, space in cause_spaces(run, base):
            candidate, fits[name] = fit_candidate(run, name, space, base)
            candidates.append({**candidate, "rays_deferred": None})
        return candidates, fits
    window = ratio_window(base.fit.theta, run.settings.cause_window_decades)
    run.on_demand = deferring
    try:
        for name, space in cause_spaces(run, base):
            # the first fit draws copies: a SeedSequence that spawned is spent
            drawn, replay = itertools.tee(run.seeds)
            run.seeds = map(copy.deepcopy, drawn)
            run.on_demand = deferring
            candidate, fit = fit_candidate(run, name, space, base)
            held = [d for d in deferring.deferred if d["cause"] in (name, None)]
            record = _record(held, candidate, margin) if held else None
            if record is not None and record["solved"]:
                run.on_demand, run.seeds = strict, replay
                candidate, fit = fit_candidate(run, name, _strict_space(run, name, window),
                                               base)
            elif record is not None:
                run.geometry_notes.append(_note(name, record, strict.tolerance, margin))
            candidates.append({**candidate, "rays_deferred": record})
            fits[name] = fit
    finally:
        run.on_demand = strict
    return candidates, fits


def _record(held: list, candidate: dict, margin: float) -> dict:
    """What was read beyond the tolerance for a cause, and whether it is solved."""
    return {"ray_sets": len(held), "rays": sum(d["rays"] for d in held),
            "largest_error_estimate": max(d["largest_error_estimate"] for d in held),
            "delta_bic_read": candidate["delta_bic"],
            "solved": bool(candidate["delta_bic"] < margin)}


def _strict_space(run, name, window):
    """The cause's space at the layers with its rays solved where the estimate is over
    the tolerance (``run.on_demand`` the strict solver); its notes replace the read's."""
    spaces, notes = run.at_layers([BASELINE, name], window)
    run.spaces[name] = spaces[name]
    own = f"{name}:"
    run.geometry_notes = ([n for n in run.geometry_notes if not n.startswith(own)]
                          + [n for n in notes if n.startswith(own)])
    return spaces[name]


def _note(name, record, tolerance, margin) -> str:
    return (f"{name}: {record['rays']} of its rays (or of the neo-Hookean ones it nests) "
            f"read off the geometry spaces with error estimates up to "
            f"{record['largest_error_estimate']:.1%}, over the {tolerance:.0%} tolerance, "
            f"and not solved: its fit with them lies {record['delta_bic_read']:+.1f} in BIC "
            f"from the neo-Hookean one, at least {margin:g} above any value that could "
            "change the verdict")
