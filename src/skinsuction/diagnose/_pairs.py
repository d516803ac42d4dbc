"""The second effect of a ramp: two causes at once, from the pair spaces.

A ramp of a skin that stiffens *and* is pre-stressed gets, from the single
causes, the one that absorbs most of both, with biased parameters.  After the
single causes are fitted (:mod:`._steps`), :func:`second_effect` takes the
lowest-BIC decisive one as the *parent* and fits every pair space that holds it
(:mod:`skinsuction.space._pairs`), started from both causes' own fits.  A pair
is added when it earns its parameter against *both* of its single causes
(ΔBIC <= ``delta_bic`` against each: the check that each chosen effect still
earns its place in the final model) and its residuals pass the smooth-pattern
test.  Pairs within ``ambiguity_bic`` of the chosen one are tied.

Pairs are simulated on the spaces' own layers (the paper's 1 mm); elsewhere,
or without pair spaces, the step says why it was not taken.
"""

from __future__ import annotations

from skinsuction.space import space_causes

from ._fit import fit_bounds, nested_start
from ._stats import bic, describe_residuals, misfit_test
from ._steps import Run, fit_json, fitted_skin, intervals_json, residual_dict

__all__ = ["second_effect", "pair_final"]


def _not_taken(why: str) -> dict:
    return {"tried": False, "why": why, "options": [], "added": None, "ambiguous_with": []}


def _usable_pairs(run: Run, pairs: dict, parent: str, fitted: dict) -> list:
    return [(name, space) for name, space in pairs.items()
            if parent in space.pair.cause_names
            and all(c in fitted for c in space.pair.cause_names)
            and all(space.has_probe(p) for p in run.probes)]


def _within_reach(run: Run, usable: list, parent_fit) -> tuple:
    """The pairs whose load reaches this curve at the parent's X1d, and why none does.

    Pair spaces built before the singles' load tail stop at its start (2·10⁴
    mbar/MPa): a curve beyond it gets no second effect, and the report says so."""
    p_max = max(float(d.pressure_mbar.max()) for d in run.fd.values())
    x1d = float(parent_fit.parameters["X1d"])
    kept = [(n, s) for n, s in usable if p_max / x1d <= s.spec.load_max * (1 + 1e-9)]
    if kept:
        return kept, None
    reach = max(s.spec.load_max for _, s in usable)
    return [], (f"the pair spaces reach p/X1d <= {reach:g} mbar/MPa and this curve needs "
                f"{p_max / x1d:.0f} at the single cause's X1d = {x1d:.4g} MPa: no second "
                "effect is tried (rebuild them: snakemake --cores 2 scale_free_pairs)")


def _starts(space, fits: dict):
    """The pair at each of its causes' own fits, the other cause at its neutral value."""
    first, second = space.pair.causes
    return [nested_start(fits[first.name].theta, second, at=3),
            nested_start(fits[second.name].theta, first, at=2)]


def _option(run: Run, name: str, space, fits: dict, by_cause: dict, parent: str) -> tuple:
    settings = run.settings
    f = run.fit(space, starts=_starts(space, fits))
    t = misfit_test(residual_dict(f, run.fd), run.sigma, run.noise.dof, settings.degree,
                    settings.alpha)
    b = bic(f.chi2, f.n_params, run.n_points)
    bounds = fit_bounds(space, run.fd, f.theta)
    other = next(c for c in space.pair.cause_names if c != parent)
    d_parent, d_other = b - by_cause[parent]["bic"], b - by_cause[other]["bic"]
    decisive = d_parent <= settings.delta_bic and d_other <= settings.delta_bic
    return {
        "model": name,
        "effects": [parent, other],
        "added": other,
        "parameters": f.parameters,
        "E_um": f.E_um,
        "bic": b,
        "delta_chi2": f.chi2 - fits[parent].chi2,
        "delta_bic": d_parent,
        # the final check: the parent must still earn its place beside the added effect
        "delta_bic_vs_added_alone": d_other,
        "decisive": bool(decisive),
        "systematic_misfit": t.significant,
        "misfit_p_value": t.p_value,
        "removes_misfit": not t.significant,
        "at_bound": bounds,
        "description": describe_residuals(t, residual_dict(f, run.fd, False), run.sigma),
        "fit": fit_json(f, t),
        "skin": fitted_skin(run, f, space_causes(space)),
        "intervals": None,
    }, f


def second_effect(run: Run, candidates: list, fits: dict, pairs: dict) -> dict:
    """Step 4: the pair of causes that adds a second effect to the first, if one earns it.

    Parameters
    ----------
    run : Run
    candidates : list of dict
        The single causes' candidates (``report["candidates"]``).
    fits : dict
        ``{cause: Fit}`` of those candidates.
    pairs : dict
        ``{name: PairRaySpace}`` (:func:`skinsuction.space.read_pair_spaces`).

    Returns
    -------
    dict
        ``tried``, ``why`` (if not), ``parent``, ``options`` (each pair's
        candidate), ``added`` (the chosen option or None), ``ambiguous_with``.
        The chosen option carries its intervals and its Fit under ``_fit``.
    """
    settings = run.settings
    if not pairs:
        return _not_taken("no pair spaces (scale_free_space.pairs) were given")
    if not run.geometry.is_default:
        return _not_taken("the pairs of causes are simulated on the space's own layers (1 mm "
                          "dermis and hypodermis); a second effect is not tried at the "
                          "subject's layers")
    decisive = [c for c in candidates if c["decisive"]]
    if not decisive:
        return _not_taken("no single cause earns its parameter, so no second effect is tried")
    parent = min(decisive, key=lambda c: c["bic"])["cause"]
    by_cause = {c["cause"]: c for c in candidates}
    usable = _usable_pairs(run, pairs, parent, by_cause)
    if not usable:
        return {**_not_taken(f"no pair space holds {parent} with another fitted cause at "
                             "these probes"), "parent": parent}
    usable, short = _within_reach(run, usable, fits[parent])
    if short:
        return {**_not_taken(short), "parent": parent}
    options, pair_fits = [], {}
    for name, space in usable:
        opt, pair_fits[name] = _option(run, name, space, fits, by_cause, parent)
        options.append(opt)
    passing = [o for o in options if o["decisive"] and o["removes_misfit"]]
    added, tied = None, []
    if passing:
        added = min(passing, key=lambda o: o["bic"])
        tied = [o["model"] for o in passing
                if o is not added and o["bic"] - added["bic"] < settings.ambiguity_bic]
        space = usable[[n for n, _ in usable].index(added["model"])][1]
        added["intervals"] = intervals_json(space, run.fd, pair_fits[added["model"]].theta,
                                            run.noise, settings)
        added["_fit"] = pair_fits[added["model"]]
    return {"tried": True, "why": None, "parent": parent, "options": options,
            "added": added, "ambiguous_with": tied}


def pair_final(base, step: dict) -> dict:
    """The report's verdict fields where a pair is the final model."""
    chosen = step["added"]
    beyond = [{"model": chosen["model"], **f} for f in chosen["at_bound"].values()
              if f["at_bound"] and not f["neutral"]]
    return {
        "cause": step["parent"],
        "effects": list(chosen["effects"]),
        "verdict": "beyond_space" if beyond else "cause_found",
        "beyond_space": beyond,
        "extended": {"cause": chosen["model"], "effects": list(chosen["effects"]),
                     "parameters": chosen["parameters"], "intervals": chosen["intervals"],
                     "E_um": chosen["E_um"], "skin": chosen["skin"]},
        "gain": {"E_ratio": chosen["E_um"] / base.fit.E_um if base.fit.E_um > 0 else None,
                 "delta_bic": chosen["bic"] - base.bic, "holdout_ratio": None},
    }
