"""The diagnosis of measured suction curves: fit, misfit, candidates, verdict, report.

:func:`diagnose` runs the five steps of ``skinsuction diagnose`` on loaded data
and the ray spaces; :func:`diagnose_file` reads the CSV and the spaces first;
:func:`write_report` writes ``report.json``, ``report.md`` and the figures.

Decision rule (settings in :class:`Settings`, defaults from
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

import datetime as _dt
import math
import time
from dataclasses import asdict, dataclass, field

import numpy as np

from skinsuction.identify import IdentificationError
from skinsuction.errors import InputError

from skinsuction.space import BASELINE, NONE
from ._fit import (PAPER_WF, FitData, fit_bounds, fit_intervals, fit_model, nested_start,
                   with_space_error)
from ._stats import (
    NoiseEstimate,
    bic,
    describe_residuals,
    misfit_test,
    noise_from_differences,
    noise_from_replicates,
)

__all__ = ["BeyondSpaceError", "BEYOND_SPACE", "Settings", "diagnose", "diagnose_file", "prepare_data"]

#: Cause and verdict where the best fit sits at an edge of the simulated space.
BEYOND_SPACE = "beyond_space"

#: Fewest points above 0 mbar per probe that a diagnosis accepts.
MIN_POINTS = 8

@dataclass(frozen=True)
class Settings:
    """Settings of a diagnosis (see the module docstring for the decision rule).

    Attributes
    ----------
    alpha : float
        Level of the smooth-pattern (systematic misfit) test.
    delta_bic : float
        A candidate's BIC must be at least this much below the baseline's (< 0).
    degree : int
        Highest Legendre degree of the smooth pattern per probe.
    model_error_um : float
        Accuracy of the simulated spaces (interpolation of the rays, µm), added in
        quadrature to the noise of each fitted point, so that data with almost no
        noise are not judged against an accuracy the spaces do not have.
    noise_um : float or None
        Noise sd of one measured deflection if known (µm); estimated otherwise.
    repeats : int
        Window focusing runs per fit (the best is polished).
    holdout : bool
        Cross-probe holdout when both probes are present.
    ambiguity_bic : float
        Eligible candidates whose BIC is within this of the chosen one's are reported
        as ``ambiguous_with`` (6: the "strong evidence" step of Kass and Raftery).
    seed : int
        Seed of the window focusing runs (>= 0).
    level : float
        Confidence level of the profile-likelihood intervals of every fit.
    intervals : {"chosen", "all"}
        Intervals of the baseline and of the chosen cause (or of the model a
        ``beyond_space`` verdict stands on), or of every candidate (about 1 s of
        CPU each on the default space).
    window_focusing : dict
        N, Nb, C, max_iter.
    space_error : bool
        Weigh the scale-free space's correlated error along each curve (its rms per
        load p / X1d, measured against direct FE runs) in every chi^2 and in the
        misfit test, as the identification's intervals do; without it a smooth
        error of the space on soft skin (a few µm at the top of a 6 mm curve) reads
        as a systematic misfit.
    cause_window_decades : float or None
        Where the causes' rays are solved on demand (a probe or layers the
        precomputed space lacks), only the X1h/X1d nodes within this many decades
        of the neo-Hookean fit are solved (about 7 of 16 at 1.0), and the window
        widens by as much where a cause's fit reaches its outer cell; None: every
        node.  The precomputed rays are used whole.
    pattern_gate : bool
        True: a cause is named only where the smooth-pattern test of the neo-Hookean
        residuals fires first (step 1 of the rule).  False: a decisive candidate that
        removes the misfit is a detection of its own (its likelihood-ratio test of one
        extra parameter is the more powerful near the noise); the pattern test then
        only tells ``unexplained_misfit`` from ``neo_hookean_fits``.
    """

    alpha: float = 0.01
    delta_bic: float = -10.0
    degree: int = 4
    model_error_um: float = 0.3
    noise_um: float | None = None
    repeats: int = 2
    holdout: bool = True
    ambiguity_bic: float = 6.0
    seed: int = 0
    level: float = 0.95
    intervals: str = "chosen"
    window_focusing: dict = field(default_factory=lambda: dict(PAPER_WF))
    space_error: bool = True
    cause_window_decades: float | None = 1.0
    pattern_gate: bool = False

    def __post_init__(self):
        if not 0 < self.alpha < 1:
            raise ValueError(f"alpha must lie in (0, 1), got {self.alpha}")
        if not self.delta_bic < 0:
            raise ValueError(f"delta_bic must be negative, got {self.delta_bic}")
        if self.noise_um is not None and not self.noise_um > 0:
            raise ValueError(f"noise_um must be positive, got {self.noise_um}")
        if self.model_error_um < 0:
            raise ValueError("model_error_um must be >= 0")
        if int(self.seed) < 0:
            raise ValueError(f"seed must be >= 0, got {self.seed}")
        if self.intervals not in ("chosen", "all"):
            raise ValueError(f"intervals must be 'chosen' or 'all', got {self.intervals!r}")
        if not 0.5 <= self.level < 1:
            raise ValueError(f"level must lie in [0.5, 1), got {self.level}")
        if not isinstance(self.pattern_gate, bool):
            raise ValueError(f"pattern_gate must be true or false, got {self.pattern_gate!r}")
        if self.cause_window_decades is not None and not self.cause_window_decades > 0:
            raise ValueError("cause_window_decades must be positive or None, got "
                             f"{self.cause_window_decades}")

    @classmethod
    def from_config(cls, decision: dict | None = None, fit: dict | None = None, **kw):
        d = dict(decision or {})
        f = dict(fit or {})
        wf = {**PAPER_WF, **(f.pop("window_focusing", None) or {})}
        allowed = cls.__dataclass_fields__
        return cls(**{k: v for k, v in {**d, **f, **kw}.items() if k in allowed},
                   window_focusing=wf)


# --------------------------------------------------------------------- the data
def prepare_data(data, probes, settings: Settings):
    """Fitted points per probe and the noise estimate.

    Replicate curves of a probe at the same pressures are averaged (the noise of
    the mean is sd / sqrt(R)); replicates at different pressures are fitted
    point by point.  Points at p = 0 are not fitted (every model gives M(0) = 0;
    a Cutometer zeroes there).
    """
    fitted, groups, singles, info = {}, [], [], {}
    for probe in probes:
        curves = data.for_probe(probe)
        if not curves:
            continue
        ps = [c.pressure_mbar for c in curves]
        aligned = len(curves) > 1 and all(
            p.shape == ps[0].shape and np.allclose(p, ps[0]) for p in ps)
        keep = [p > 0 for p in ps]
        for c, k in zip(curves, keep):
            singles.append((c.pressure_mbar[k], c.deflection_mm[k]))
        if aligned:
            y = np.array([c.deflection_mm[keep[0]] for c in curves])
            groups.append(y)
            p, m, n_rep = ps[0][keep[0]], y.mean(axis=0), len(curves)
        else:
            p = np.concatenate([c.pressure_mbar[k] for c, k in zip(curves, keep)])
            m = np.concatenate([c.deflection_mm[k] for c, k in zip(curves, keep)])
            order = np.argsort(p, kind="stable")
            p, m, n_rep = p[order], m[order], 1
        fitted[float(probe)] = (p, m, n_rep, tuple(c.curve for c in curves))
        info[f"{probe:g}"] = {"curves": [c.curve for c in curves], "replicates": len(curves),
                              "averaged": bool(aligned), "points_fitted": int(p.size)}
    if not fitted:
        raise InputError(f"{data.path}: no curve of a probe the spaces cover")
    need = max(MIN_POINTS, settings.degree + 3)
    for probe, (p, *_rest) in fitted.items():
        if p.size < need:
            raise InputError(
                f"{data.path}: the {probe:g} mm curve has {p.size} points above 0 mbar; the "
                f"diagnosis needs at least {need} (the smooth-pattern test fits "
                f"{settings.degree + 1} Legendre terms per probe and the noise needs differences)")
    if settings.noise_um is not None:
        noise = NoiseEstimate(float(settings.noise_um), "given", math.inf, {})
    elif groups:
        noise = noise_from_replicates(groups)
    else:
        noise = noise_from_differences(singles)
    out = {}
    for probe, (p, m, n_rep, ids) in fitted.items():
        sd = math.sqrt(noise.sd_um ** 2 / n_rep + settings.model_error_um ** 2)
        out[probe] = FitData(probe, p, m, sd, ids)
    return out, noise, info


# --------------------------------------------------------------------- diagnose
class BeyondSpaceError(InputError):
    """No candidate of the simulated space has a curve over the measured pressures."""


def _beyond_message(space, fd) -> str:
    spec = space.spec
    p_max = max(float(d.pressure_mbar.max()) for d in fd.values())
    return (f"beyond_space: no neo-Hookean curve of the scale-free space covers the "
            f"measurement up to {p_max:g} mbar (X1d >= {spec.x1d_lower(p_max):.3g} MPa is "
            f"searched, and the FE rays stop before the load p/X1d the fit needs: see "
            f"results/tables/scale_free_coverage.csv); widen scale_free_space.load.max, "
            f"scale_free_space.mesh_fallback or scale_free_space.x1d_mpa")


def _intervals(space, fd, theta, noise, settings):
    """The fit's profile-likelihood intervals as JSON (None, with the reason, if they fail)."""
    try:
        return fit_intervals(space, fd, theta, noise_dof=noise.dof,
                             level=settings.level).to_dict()
    except ValueError as err:
        return {"error": str(err)}


def _residual_dict(fit, data, independent=True):
    """{probe: (pressure, residual µm)}: by default with the space's correlated error
    taken out (what the misfit test judges), else as measured minus fitted."""
    res = fit.independent_um if independent else fit.residual_um
    return {p: (data[p].pressure_mbar, res[p]) for p in data}


def _fit_json(fit, test=None):
    return {
        "parameters": fit.parameters,
        "E_um": fit.E_um,
        "rms_um": fit.rms_um,
        "chi2": fit.chi2,
        "n_points": fit.n_points,
        "n_params": fit.n_params,
        "fitted_mm": {f"{p:g}": _finite(c) for p, c in fit.fitted_mm.items()},
        "residual_um": {f"{p:g}": _finite(c) for p, c in fit.residual_um.items()},
        "misfit_test": test.to_dict() if test is not None else None,
        "optimiser": fit.wf,
    }


def _finite(a):
    return [float(x) if np.isfinite(x) else None for x in np.asarray(a, dtype=float)]


def _holdout(space, data, settings, seed):
    """Fit on one probe alone, predict the other.

    Returns (E of the holdout in µm, detail).  The holdout E is that of the
    smaller probe predicted from a fit of the larger one (6 -> 2 mm): the paper
    (section 3.2, Figure 4) shows that the 6 mm probe identifies both layers and
    the 2 mm probe alone cannot identify X1h, so the other direction fails for
    every model; it is reported in the detail.
    """
    from ._fit import ModelCurves

    probes = sorted(data)
    small, large = probes[0], probes[-1]
    detail, main = {}, None
    for train, test in ((large, small), (small, large)):
        f = fit_model(space, {train: data[train]}, seed=seed, repeats=1,
                      window_focusing_options=settings.window_focusing)
        pred = ModelCurves(space, {test: data[test]})(f.theta[None, :])[test][0]
        e = 1e3 * (data[test].deflection_mm - pred)
        s = float((e ** 2).sum())
        ok = math.isfinite(s)
        d = {"parameters": f.parameters, "E_um": math.sqrt(s) / e.size if ok else None,
             "rms_um": math.sqrt(s / e.size) if ok else None}
        detail[f"fit_{train:g}_predict_{test:g}"] = d
        if main is None:
            main = d["E_um"]
    return main, detail


def ratio_window(theta, decades: float) -> tuple:
    """X1h/X1d within ``decades`` of a fit's ``theta = (log10 X1d, log10 X1h/X1d, ...)``."""
    r, half = 10.0 ** float(theta[1]), 10.0 ** float(decades)
    return (r / half, r * half)


def widened_window(nodes, ratio: float, full, decades: float):
    """The wider window when ``ratio`` lies in an outer cell of the cut ``nodes``.

    Widened by as many of the ``full`` nodes as ``decades`` spans (at least one) on
    that side; None when ``ratio`` is inside, or the cut already reaches that end.

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

    ``rebuild(window) -> (space, notes)`` gives the cause's space over a wider
    window, ``refit(space, previous_fit) -> fit`` fits it again; a space with
    every node is returned as it is.  Returns ``(space, fit, notes)``: the notes
    say each widening.
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


def _eligible(candidate: dict) -> bool:
    """Step 2 of the rule: the candidate earns its parameter and removes the misfit."""
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
    eligible = [c for c in candidates if _eligible(c)]
    # with pattern_gate off a decisive candidate is a detection of its own: its
    # targeted likelihood ratio sees a one-parameter effect that the generic
    # pattern test (k = 5 per probe) misses near the noise
    detected = base_misfit or not settings.pattern_gate
    if detected and eligible:
        best = min(eligible, key=lambda c: c["bic"])
        # candidates that explain the data about as well (BIC within ambiguity_bic): the
        # curves cannot separate them; the lowest BIC is named, the others reported
        tied = [c for c in eligible if c["bic"] - best["bic"] < settings.ambiguity_bic]
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


def diagnose(data, spaces: dict, settings: Settings | None = None, *, source=None,
             geometry=None, on_demand=None) -> dict:
    """Diagnose loaded measured data (:class:`skinsuction.measured.MeasuredData`).

    Parameters
    ----------
    data : MeasuredData
    spaces : dict name -> RaySpace
        ``neo_hookean`` and the candidate causes (see :func:`read_ray_spaces`).
    settings : Settings
    source : dict, optional
        ``{"file": ..., "sha256": ...}`` of the input file for the report.
    geometry : skinsuction.space.Geometry, optional
        The layer thicknesses; by default those of the file's header lines (or a
        study's columns), else the paper's 1 mm, stated as assumptions.  A given
        thickness takes its cause out of the candidates.
    on_demand : skinsuction.space.OnDemandRays, optional
        Solves the neo-Hookean rays of a probe or layers the spaces lack; without
        it such data raise an InputError.

    Returns
    -------
    dict
        The report (see the package docstring for its contract).
    """
    from skinsuction.measured import geometry_of
    from skinsuction.space import GeometryOutsideSpace, spaces_at

    t0, c0 = time.perf_counter(), time.process_time()
    settings = settings or Settings()
    geometry_warnings = []
    if geometry is None:
        geometry, geometry_warnings = geometry_of(data)
    given_spaces = spaces
    # with rays on demand the causes' X1h/X1d window is centred on the baseline's fit:
    # the baseline's space first, the causes' after it is fitted
    windowed = on_demand is not None and settings.cause_window_decades is not None

    def at_layers(names, window=None):
        try:
            return spaces_at({n: given_spaces[n] for n in names}, data.probes, geometry,
                             on_demand, ratio_window=window)
        except GeometryOutsideSpace as err:
            raise InputError(f"{data.path}: {err}") from None

    spaces, geometry_notes = at_layers([BASELINE] if windowed else list(given_spaces))
    base_space = spaces[BASELINE]
    probes = [p for p in data.probes if base_space.has_probe(p)]
    skipped = [p for p in data.probes if not base_space.has_probe(p)]
    fd, noise, data_info = prepare_data(data, probes, settings)
    probes = sorted(fd)
    root = np.random.SeedSequence(settings.seed)
    seeds = iter(root.spawn(64))
    sigma = {p: fd[p].sigma_um for p in probes}
    n_points = sum(d.n for d in fd.values())

    # 1. baseline
    try:
        base = fit_model(base_space, fd, seed=next(seeds), repeats=settings.repeats,
                         window_focusing_options=settings.window_focusing)
    except IdentificationError:
        raise BeyondSpaceError(_beyond_message(base_space, fd)) from None
    if settings.space_error:
        # the space's error grows with the load p / X1d: weigh it at the baseline's X1d,
        # then polish the baseline under that likelihood, as every cause is fitted
        fd = with_space_error(fd, base.parameters["X1d"])
        searched = base.wf
        base = fit_model(base_space, fd, seed=0, repeats=0, starts=[base.theta],
                         window_focusing_options=settings.window_focusing)
        base.wf = {**searched, "space_error_polished": base.wf["polished"]}
    base_test = misfit_test(_residual_dict(base, fd), sigma, noise.dof, settings.degree,
                            settings.alpha)
    base_bic = bic(base.chi2, base.n_params, n_points)
    base_bounds = fit_bounds(base_space, fd, base.theta)
    base_ci = _intervals(base_space, fd, base.theta, noise, settings)
    two_probes = len(probes) >= 2 and settings.holdout
    base_hold, base_hold_detail = (_holdout(base_space, fd, settings, next(seeds))
                                   if two_probes else (None, None))

    # 2. candidates
    full_ratio = base_space.spec.ratio_nodes
    if windowed:
        spaces, geometry_notes = at_layers(
            list(given_spaces), ratio_window(base.theta, settings.cause_window_decades))
        spaces[BASELINE] = base_space
    candidates, fits, tests = [], {}, {}
    for name, space in spaces.items():
        if name == BASELINE:
            continue
        if not all(space.has_probe(p) for p in probes):
            continue
        cause = space.cause
        null_theta = nested_start(base.theta, cause)
        f = fit_model(space, fd, seed=next(seeds), repeats=settings.repeats,
                      window_focusing_options=settings.window_focusing, starts=[null_theta])
        if windowed:
            def rebuild(window, name=name):
                wider, notes = at_layers([BASELINE, name], window)
                return wider[name], [n for n in notes if n.startswith(f"{name}:")]

            def refit(space, previous, null_theta=null_theta):
                return fit_model(space, fd, seed=next(seeds), repeats=settings.repeats,
                                 window_focusing_options=settings.window_focusing,
                                 starts=[previous.theta, null_theta])

            space, f, notes = fit_in_window(space, f, full_ratio,
                                            settings.cause_window_decades, rebuild, refit)
            spaces[name] = space
            geometry_notes += notes
        t = misfit_test(_residual_dict(f, fd), sigma, noise.dof, settings.degree,
                        settings.alpha)
        b = bic(f.chi2, f.n_params, n_points)
        hold, hold_detail = (_holdout(space, fd, settings, next(seeds))
                             if two_probes else (None, None))
        fits[name], tests[name] = f, t
        bounds = fit_bounds(space, fd, f.theta)
        candidates.append({
            "intervals": (_intervals(space, fd, f.theta, noise, settings)
                          if settings.intervals == "all" else None),
            "cause": name,
            "hypothesis": cause.hypothesis,
            "parameters": f.parameters,
            "E_um": f.E_um,
            "delta_bic": b - base_bic,
            "holdout_E_um": hold,
            "E_ratio": f.E_um / base.E_um if base.E_um > 0 else None,
            "holdout_ratio": (hold / base_hold) if hold is not None and base_hold else None,
            "delta_chi2": f.chi2 - base.chi2,
            "bic": b,
            "systematic_misfit": t.significant,
            "misfit_p_value": t.p_value,
            "decisive": bool(b - base_bic <= settings.delta_bic),
            "removes_misfit": not t.significant,
            "extra_parameter": {"symbol": cause.symbol, "unit": cause.unit,
                                "value": f.parameters[cause.symbol],
                                "coordinate": float(cause.from_axis(f.theta[2])),
                                "coordinate_name": cause.coordinate_name,
                                "range": [cause.lower, cause.upper],
                                "at_bound": bounds[cause.symbol]["at_bound"]
                                and not bounds[cause.symbol]["neutral"]},
            "at_bound": bounds,
            "fit": _fit_json(f, t),
            "holdout": hold_detail,
        })

    # 3. verdict
    best, cause, verdict, ambiguous, beyond, standing = decide(
        base_test.significant, base_bic, base_bounds, candidates, settings)
    # the intervals of the model the verdict stands on (the others' with intervals="all")
    for c in candidates:
        if c["intervals"] is None and c["cause"] == standing:
            c["intervals"] = _intervals(spaces[c["cause"]], fd, fits[c["cause"]].theta, noise,
                                        settings)
    ranked = sorted(candidates, key=lambda c: c["bic"])
    runner_up = next((c for c in ranked if best is not None and c is not best), None)

    from ._creep import untestable_on_ramps

    description = describe_residuals(base_test, _residual_dict(base, fd, False), sigma)
    report = {
        "input": {**(source or {}), "probes_mm": [float(p) for p in probes],
                  "probes_skipped_mm": [float(p) for p in skipped],
                  "metadata": dict(getattr(data, "metadata", {}) or {}),
                  "warnings": list(getattr(data, "warnings", ()) or ()) + geometry_warnings,
                  "curves": data_info},
        "geometry": {**geometry.to_dict(), "notes": geometry_notes},
        "noise_um": noise.sd_um,
        "noise": {**noise.to_dict(),
                  "sigma_fitted_um": {f"{p:g}": sigma[p] for p in probes},
                  "model_error_um": settings.model_error_um},
        "baseline": {
            "model": BASELINE,
            "parameters": base.parameters,
            "E_um": base.E_um,
            "systematic_misfit": base_test.significant,
            "description": description,
            "bic": base_bic,
            "holdout_E_um": base_hold,
            "holdout": base_hold_detail,
            "at_bound": base_bounds,
            "intervals": base_ci,
            **{k: v for k, v in _fit_json(base, base_test).items() if k != "parameters"},
        },
        "data": {f"{p:g}": {"pressure_mbar": fd[p].pressure_mbar.tolist(),
                            "measured_mm": fd[p].deflection_mm.tolist(),
                            "sigma_um": fd[p].sigma_um} for p in probes},
        "candidates": candidates,
        # causes that a pressure ramp cannot test, and why
        "untestable": [untestable_on_ramps()],
        "cause": cause,
        "verdict": verdict,
        # which test saw the effect: the generic smooth-pattern test of the neo-Hookean
        # residuals, and/or a candidate's own BIC (decisive and removing the misfit)
        "detection": {"pattern_test": bool(base_test.significant),
                      "candidate_bic": any(map(_eligible, candidates))},
        "beyond_space": beyond,
        "extended": ({"cause": best["cause"], "parameters": best["parameters"],
                      "intervals": best["intervals"], "E_um": best["E_um"]} if best else None),
        "gain": ({"E_ratio": best["E_ratio"], "delta_bic": best["delta_bic"],
                  "holdout_ratio": best["holdout_ratio"]} if best else None),
        "runner_up": ({"cause": runner_up["cause"],
                       "bic_above_chosen": runner_up["bic"] - best["bic"],
                       "holdout_E_um": runner_up["holdout_E_um"]}
                      if runner_up else None),
        "ambiguous_with": ambiguous,
        "summary": None,
        "settings": {**asdict(settings), "n_points": n_points},
        "spaces": {name: {"x1d_range_mpa": list(s.spec.x1d_range),
                          "load_max_mbar_per_mpa": s.spec.load_max,
                          "x1h_over_x1d_range": [s.spec.ratio_nodes[0], s.spec.ratio_nodes[-1]],
                          "coordinate_range": ([s.cause.lower, s.cause.upper]
                                               if s.cause else None),
                          "mesh": s.spec.mesh, "git_commit": (s.metadata.get("git") or {})
                          .get("commit")} for name, s in spaces.items()},
        "seconds": None,
    }
    report["summary"] = summary_text(report)
    report["seconds"] = time.perf_counter() - t0
    report["cpu_seconds"] = time.process_time() - c0
    from skinsuction import __version__

    report["skinsuction_version"] = __version__
    report["created_utc"] = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")
    return report


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
    """The verdict in two or three plain sentences."""
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


def diagnose_file(measured_path, space_dir=None, settings: Settings | None = None,
                  spaces: dict | None = None, *, thickness: dict | None = None,
                  on_demand=None, workers: int = 1) -> dict:
    """Read a measured CSV (as ``skinsuction identify`` does) and diagnose it.

    ``measured_path`` may be the file's curves as read
    (:func:`skinsuction.measured.read_measurement`): checked against the spaces,
    not read again.

    ``space_dir``: the scale-free space; by default the workflow's build in
    ``results/simulated_space/scale_free`` of the working directory if there is
    one, else the default space shipped with skinsuction
    (:func:`skinsuction.space.resolve_space`).  ``input.space`` of the report
    says which.  ``spaces``: the ray spaces already read (from ``space_dir``).
    ``thickness``: ``dermis_thickness_mm`` ... overriding the file's header lines.
    ``on_demand``: an :class:`skinsuction.space.OnDemandRays`, False to refuse a
    probe or layers the spaces lack, or None to solve them (``workers`` processes).
    """
    from skinsuction._files import file_sha256
    from skinsuction.measured import MeasuredData, check_against_space, geometry_of, load_measured

    from skinsuction.space import OnDemandRays, read_ray_spaces, resolve_space

    if spaces is None or space_dir is not None:
        src = resolve_space(space_dir)
        space_dir, space_info = src.path, src.info()
    else:
        space_info = {"source": "given", "description": "ray spaces given in memory"}
    if spaces is None:
        spaces = read_ray_spaces(space_dir)
    base = spaces[BASELINE]
    sp = base.spec
    data = (measured_path if isinstance(measured_path, MeasuredData)
            else load_measured(measured_path))
    check_against_space(data, available_probes=None if on_demand is not False
                        else list(base.probes_mm),
                        pressure_range_mbar=(0.0, sp.reach_mbar()),
                        range_note=(f"the reach of the scale-free space: p/X1d <= "
                                    f"{sp.load_max:g} mbar/MPa up to X1d = "
                                    f"{sp.x1d_range[1]:g} MPa"))
    source = {"file": data.path, "sha256": file_sha256(data.path),
              "space_dir": str(space_dir) if space_dir is not None else None,
              "space": space_info}
    geometry, warnings = geometry_of(data, **(thickness or {}))
    solver = None
    if on_demand is not False:
        solver = on_demand if on_demand not in (None, True) else OnDemandRays(sp, workers=workers)
    report = diagnose(data, spaces, settings, source=source, geometry=geometry, on_demand=solver)
    report["input"]["warnings"] = warnings + report["input"]["warnings"]
    return report
