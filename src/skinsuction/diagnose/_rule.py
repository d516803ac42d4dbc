"""The decision rule of a diagnosis: the verdict from the fits of the baseline and the causes.

The rule (settings in :class:`Settings`, defaults from
``diagnosis.decision`` of the configuration):

1. a *detection*: a candidate passes step 2 (its likelihood-ratio test of one
   extra parameter, the most powerful test of that effect), or the baseline
   (neo-Hookean) fit has a *systematic misfit*: the smooth-pattern test of its
   residuals rejects pure noise at level ``alpha`` (0.01).  With ``pattern_gate``
   on (the rule until 26 November 2026) only the pattern test detects; it has k = 5
   degrees per probe against the candidate's 1, and misses effects near the noise
   that a candidate sees (docs/diagnosis.md, "Detection near the noise");
2. a candidate *earns its extra parameter* if ``delta_BIC <= delta_bic``
   (-10: "very strong" evidence on the scale of Kass and Raftery, 1995; with
   ln n ~ 4.6 for 100 points this asks the extra parameter to lower chi^2 by
   more than 14.6, which pure noise does with probability ~1e-4) **and** its
   own residuals pass the smooth-pattern test (it removes the misfit);
3. the cause is the candidate of lowest BIC among those; ``none`` otherwise.
   With a misfit that no candidate removes the verdict is ``none`` with
   ``verdict = "unexplained_misfit"``;
4. ties: eligible candidates whose BIC lies within ``ambiguity_bic`` (6, the
   "strong evidence" step of Kass and Raftery) of the chosen one are reported
   as ``ambiguous_with``: the curves cannot tell them apart.  (A thicker dermis
   and a pre-tension change the 2 and 6 mm curves almost alike; breaking their
   tie by the cross-probe holdout was tried and did no better than the BIC.)

The cross-probe holdout is measured and reported for every model when both
probes are present.  Its E is that of the 2 mm curve predicted from a fit of
the 6 mm curve: the 6 mm probe identifies both layers, the 2 mm probe alone
does not identify X1h (paper section 3.2), so the other direction fails for
every model (it is in the detail).  With three parameters a single curve can
leave a valley of near-equal fits, so the holdout is noisy; it is not part of
the rule.
"""


from __future__ import annotations

from skinsuction.space import BASELINE, NONE

from ._settings import Settings

__all__ = ["BEYOND_SPACE", "decide", "eligible"]

#: Cause and verdict where the best fit sits at an edge of the simulated space.
BEYOND_SPACE = "beyond_space"


def eligible(candidate: dict) -> bool:
    """Step 2 of the rule: the candidate earns its parameter and removes the misfit.

    Parameters
    ----------
    candidate : dict
        A candidate of the report, with ``decisive`` and ``removes_misfit``.

    Returns
    -------
    bool
    """
    return bool(candidate["decisive"] and candidate["removes_misfit"])


def decide(base_misfit: bool, base_bic: float, base_bounds: dict, candidates: list,
           settings: Settings):
    """Steps 1, 3 and 4 of the rule: the verdict from the fits (module docstring).

    Parameters
    ----------
    base_misfit : bool
        Whether the smooth-pattern test rejects the neo-Hookean residuals as noise.
    base_bic : float
        BIC of the neo-Hookean fit.
    base_bounds : dict
        Its parameters' edge flags (:func:`skinsuction.diagnose._fit.fit_bounds`).
    candidates : list of dict
        One per cause, with ``cause``, ``bic``, ``decisive``, ``removes_misfit`` and
        ``at_bound``, as in the report.
    settings : Settings

    Returns
    -------
    tuple
        ``(best, cause, verdict, ambiguous, beyond, standing)``: the chosen candidate
        (or None), the cause's name, the verdict, the tied causes, the edge flags of
        the model the verdict stands on, and that model's name.
    """
    passing = [c for c in candidates if eligible(c)]
    # with pattern_gate off a decisive candidate is a detection of its own: its
    # targeted likelihood ratio sees a one-parameter effect that the generic
    # pattern test (k = 5 per probe) misses near the noise
    detected = base_misfit or not settings.pattern_gate
    if detected and passing:
        best = min(passing, key=lambda c: c["bic"])
        # candidates that explain the data about as well (BIC within ambiguity_bic): the
        # curves cannot separate them; the lowest BIC is named, the others reported
        tied = [c for c in passing if c["bic"] - best["bic"] < settings.ambiguity_bic]
        cause, verdict = best["cause"], "cause_found"
        ambiguous = [c["cause"] for c in tied if c is not best]
    else:
        best, cause, ambiguous = None, NONE, []
        verdict = "unexplained_misfit" if base_misfit else "neo_hookean_fits"
    # never a silent bound: the model the verdict stands on (the named cause, else the
    # lowest BIC of all) must not sit at an edge of the simulated space
    if best is not None:
        standing = (best["cause"], best["at_bound"])
    else:
        lowest = min(candidates, key=lambda c: c["bic"], default=None)
        standing = ((lowest["cause"], lowest["at_bound"])
                    if lowest is not None and lowest["bic"] < base_bic
                    else (BASELINE, base_bounds))
    beyond = [{"model": standing[0], **f} for f in standing[1].values()
              if f["at_bound"] and not f["neutral"]]
    if beyond:
        verdict = "beyond_space"
        if cause == NONE:
            cause = standing[0] if standing[0] != BASELINE else BEYOND_SPACE
    return best, cause, verdict, ambiguous, beyond, standing[0]
