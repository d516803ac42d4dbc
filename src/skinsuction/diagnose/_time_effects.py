"""Time curves: the diagnosis builds the model effect by effect.

Real skin creeps and stiffens at once (published Cutometer R5 < 1 needs both,
docs/effects.md), so a time curve is diagnosed by forward selection over the
effects a time curve can show:

* ``viscoelastic_creep``: one Prony term over both layers (g, tau), and once it is
  in, ``creep_second_term``: a second term (a spectrum of two, as the literature's
  10 ms and 0.1-1 s), a refinement of creep, not an effect of its own;
* each elastic cause of the space (strain stiffening X2d, pre-tension lambda0, a
  layer thickness not given): the fast path then drives the nonlinear elastic
  curve of that skin (:class:`skinsuction.identify.TimeCurveModel` on the
  cause's rays).

A model is a set of effects with at most one elastic cause (a ray space holds one
cause coordinate).  From the neo-Hookean stack, each step fits every model with
one effect more and adds the one of lowest BIC while it is decisive: the model
it extends misfits (chi^2 above its ``1 - alpha`` quantile) and the BIC falls by
at least ``|delta_bic|`` (the rule of the single-cause time diagnosis before).
A model that does not misfit ends the selection without fitting its options
(none could be decisive); creep alone is always fitted, for the report.  Models
within ``ambiguity_bic`` of the chosen one that are decisive too are tied
(``ambiguous_with``).  Then each chosen effect is checked against the final
model: the model without it must lie ``|delta_bic|`` above, or the effect is
dropped (``removed``).

What no model explains is described in words, not forced into a parameter: a
first cycle that departs from the later ones (preconditioning) and the misfit
left per phase.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np
from scipy import stats

from ._creep import VISCOELASTIC_CREEP
from ._stats import bic

__all__ = ["CREEP_SECOND_TERM", "TimeModel", "EffectFitter", "select_effects", "model_name",
           "physical_effects"]

#: Name of the model without effects.
BASELINE_NAME = "neo_hookean"
#: The refinement of creep: a second Prony term.
CREEP_SECOND_TERM = "creep_second_term"


def model_name(effects) -> str:
    """``"neo_hookean"`` or the effects joined by ``+`` in the order added.

    >>> model_name(()), model_name(("viscoelastic_creep", "strain_stiffening"))
    ('neo_hookean', 'viscoelastic_creep+strain_stiffening')
    """
    return "+".join(effects) if effects else BASELINE_NAME


def physical_effects(effects) -> list:
    """The effects of a model as reported: the second creep term is creep's.

    >>> physical_effects(("viscoelastic_creep", "creep_second_term", "pre_tension"))
    ['viscoelastic_creep', 'pre_tension']
    """
    return [e for e in effects if e != CREEP_SECOND_TERM]


def _terms(key) -> int:
    return int(VISCOELASTIC_CREEP in key) + int(CREEP_SECOND_TERM in key)


def _elastic(key):
    return next((e for e in key if e not in (VISCOELASTIC_CREEP, CREEP_SECOND_TERM)), None)


@dataclass
class TimeModel:
    """One fitted model: its effects (in the order added), the fit, the rays it used;
    with the FE correction, the data less the fast path's error (``data``) and the
    correction's record (``correction``)."""

    effects: tuple
    fit: object  # TimeFit
    rays: dict
    chi2: float
    n_params: int
    n_points: int
    data: list | None = field(default=None, repr=False)
    correction: dict | None = None

    @property
    def name(self) -> str:
        return model_name(self.effects)

    @property
    def bic(self) -> float:
        return bic(self.chi2, self.n_params, self.n_points)

    @property
    def misfit_p(self) -> float:
        return float(stats.chi2.sf(self.chi2, max(self.n_points - self.n_params, 1)))

    @property
    def elastic_cause(self) -> str | None:
        return _elastic(self.effects)

    @property
    def terms(self) -> int:
        return _terms(self.effects)

    @property
    def held(self) -> bool:
        """Its FE correction stopped at the first step: a nested model's error held."""
        return bool((self.correction or {}).get("held"))


class EffectFitter:
    """Fits (and caches) the model of any set of effects on prepared time curves.

    Parameters
    ----------
    prep : dict
        :func:`skinsuction.identify.time_curves.prepare_time_fit`'s output.
    settings : Settings
    causes : list of str
        The elastic causes tried (their rays: ``prep["space"].cause_rays``).
    creep : FittedTimeModel, optional
        Creep alone, fitted already (the identification's): the model of
        ``(viscoelastic_creep,)`` where it was fitted to these curves with the
        settings' FE steps (``reused`` in its correction record).

    With ``settings.fe_correction`` steps, every fit with creep is corrected by FE
    time solves at the fit (:func:`skinsuction.identify.fe_corrected_fit`); an
    elastic fit needs none (the fast path is then the rays themselves).
    """

    def __init__(self, prep: dict, settings, causes, creep=None):
        self.prep, self.settings = prep, settings
        self.data = prep["data"]
        self.probes = sorted(prep["rays"])
        root = np.random.SeedSequence(int(settings.seed))
        # the elastic and creep fits keep the seeds they had before effects composed
        self._seeds = dict(zip([(), (VISCOELASTIC_CREEP,)], root.spawn(2)))
        self._seed = int(settings.seed)
        self.notes, self.rays = [], {None: prep["rays"]}
        #: the fits whose FE correction stopped (the fast fit kept): warnings
        self.correction_failures = []
        for name in causes:
            rays, notes = prep["space"].cause_rays(name, self.probes)
            self.notes += [n for n in notes if n not in self.notes]
            if rays:
                self.rays[name] = rays
        self.causes = [c for c in causes if c in self.rays]
        self._cache = {}
        if creep is not None and creep.fits(self.data, 1, int(settings.fe_correction),
                                            geometry=prep["geometry"]):
            fit = creep.fit
            self._cache[(VISCOELASTIC_CREEP,)] = TimeModel(
                (VISCOELASTIC_CREEP,), fit, self.rays[None], float(fit.chi2),
                int(fit.n_params), int(fit.n_points), list(creep.data),
                {**creep.correction, "reused": True})

    def addable(self, effects) -> list:
        """The effects one step may add to ``effects`` (one elastic cause at most; the
        second creep term once creep is in)."""
        if VISCOELASTIC_CREEP not in effects:
            out = [VISCOELASTIC_CREEP]
        else:
            out = [] if CREEP_SECOND_TERM in effects else [CREEP_SECOND_TERM]
        if not any(e in self.causes for e in effects):
            out += self.causes
        return out

    def _seed_of(self, key):
        if key in self._seeds:
            return self._seeds[key]
        cause = _elastic(key)
        index = 2 + 3 * (self.causes.index(cause) + 1 if cause else 0) + _terms(key)
        return np.random.SeedSequence(self._seed, spawn_key=(index,))

    def fit(self, effects, finish: bool = True) -> TimeModel:
        """The model of ``effects`` (cached by set: the order only names it).

        ``finish=False``: a model that adds an effect to an FE-corrected one stops its
        correction at the held first step (no FE solve, :attr:`TimeModel.held`); a
        later call with ``finish=True`` completes it, to the same model as at once."""
        from skinsuction.identify import fit_time_model

        key = tuple(sorted(effects, key=lambda e: (e != VISCOELASTIC_CREEP, e)))
        if key not in self._cache:
            cause, terms = _elastic(key), _terms(key)
            rays = self.rays[cause]
            # the most specific nested fits first (the elastic fit alone starts creep's)
            nested = sorted(self._cache.values(), key=lambda m: -len(m.effects))
            starts = [s for s in (self._start(key, m) for m in nested) if s is not None]
            fit = fit_time_model(rays, self.data, terms=terms, seed=self._seed_of(key),
                                 repeats=self.settings.repeats, starts=starts[:2])
            data, correction = self.data, None
            if terms and self.settings.fe_correction:
                fit, data, correction = self._corrected(fit, rays, cause, key,
                                                        warm=self._corrected_parent(key))
            self._cache[key] = TimeModel(tuple(effects), fit, rays, float(fit.chi2),
                                         int(fit.n_params), int(fit.n_points), data,
                                         correction)
        if finish and self._cache[key].held:
            self._cache[key] = self._finish(self._cache[key], key)
        model = self._cache[key]
        if model.effects != tuple(effects):  # the same fit, named in this order
            model = dataclasses.replace(model, effects=tuple(effects))
        return model

    def _corrected_parent(self, key):
        """The most specific model nested in ``key`` corrected by FE time solves, or None."""
        nested = [m for m in self._cache.values() if set(m.effects) < set(key)
                  and (m.correction or {}).get("applied") and not m.held]
        return max(nested, key=lambda m: len(m.effects), default=None)

    def _finish(self, model: TimeModel, key) -> TimeModel:
        """A held model's FE correction completed from its held fit."""
        from skinsuction.identify import fe_corrected_fit

        steps, held = int(self.settings.fe_correction), model.correction
        try:
            fit, data, record = fe_corrected_fit(
                model.rays, self.data, model.fit, self._skin_of(model.rays, _elastic(key)),
                iterations=steps - 1, seed=self._seed_of(key))
        except RuntimeError as err:
            self.correction_failures.append(f"{model_name(key)}: the FE correction stopped "
                                            f"({err}); the fit holds {held['warm_start']}'s")
            return dataclasses.replace(model, correction={**held, "held": False,
                                                          "stopped": str(err)})
        record = {**record, "iterations": steps, "warm_start": held["warm_start"],
                  "chi2": [held["chi2"][0], *record["chi2"]]}
        return dataclasses.replace(model, fit=fit, chi2=float(fit.chi2), data=data,
                                   correction=record)

    def _skin_of(self, rays, cause):
        from skinsuction.identify import time_fit_skin

        c = rays[self.probes[0]].cause if cause is not None else None
        geometry, bottom = self.prep["geometry"], self.prep["space"].bottom
        return lambda parameters: time_fit_skin(parameters, geometry, bottom, c)

    def _corrected(self, fit, rays, cause, key, data=None, layers=False, warm=None):
        """The fit corrected by FE time solves; the fast fit, said so, if one stops.

        ``warm``, a corrected model nested in this one: its fast-path error, measured
        at a skin near this fit, is held for the first step (a fit without an FE
        solve), so a model that adds an effect to a corrected one pays for one FE
        solve per curve fewer: it returns that held step, :meth:`_finish` goes on."""
        from skinsuction.identify import fe_corrected_fit, fit_time_model

        skin_of = self._skin_of(rays, cause)
        data = self.data if data is None else data
        steps, fast_chi2 = int(self.settings.fe_correction), float(fit.chi2)
        warm = warm if steps > 1 and warm is not None and warm.data is not None else None
        try:
            if warm is not None:
                fit = fit_time_model(rays, warm.data, terms=fit.terms, seed=self._seed_of(key),
                                     repeats=0, starts=[fit.theta], layers=layers)
                return fit, warm.data, {"applied": True, "held": True, "warm_start": warm.name,
                                        "chi2": [fast_chi2, float(fit.chi2)]}
            return fe_corrected_fit(rays, data, fit, skin_of, iterations=steps,
                                    seed=self._seed_of(key), layers=layers)
        except RuntimeError as err:
            note = (f"{model_name(key)}{' (a spectrum per layer)' if layers else ''}: the FE "
                    f"correction stopped ({err}); the fit is the fast path's, with its model "
                    "error")
            self.correction_failures.append(note)
            return fit, data, {"applied": False, "reason": note}

    def _start(self, key, nested: TimeModel):
        """A start for ``key`` from a fitted model nested in it: the nested theta with
        the missing effect at its neutral value (a mild spectrum for creep)."""
        have = set(nested.effects)
        if not have < set(key) or not nested.fit.finite:
            return None
        theta = np.asarray(nested.fit.theta, dtype=float)
        cause = _elastic(key)
        if cause is not None and cause not in have:
            c = self.rays[cause][self.probes[0]].cause
            theta = np.concatenate([theta[:2], [c.to_axis(c.neutral)], theta[2:]])
        if VISCOELASTIC_CREEP in key and VISCOELASTIC_CREEP not in have:
            theta = np.concatenate([theta, [math.log10(0.3), math.log10(0.5)]])
        if CREEP_SECOND_TERM in key and CREEP_SECOND_TERM not in have:
            # a small fast term beside the fitted one (the literature's 10 ms)
            theta = np.concatenate([theta, [math.log10(0.05), math.log10(0.01)]])
        return theta


def _option(model: TimeModel, parent: TimeModel, settings) -> dict:
    d = model.bic - parent.bic
    corr = model.correction or {}
    return {"model": model.name, "effects": list(model.effects), "chi2": model.chi2,
            "bic": model.bic, "delta_bic": float(d), "delta_chi2": model.chi2 - parent.chi2,
            "decisive": bool(d <= settings.delta_bic and parent.misfit_p < settings.alpha),
            "fast_path_chi2": corr["chi2"][0] if corr.get("applied") else None,
            "fe_correction_from": corr.get("warm_start"), "fe_correction_held": model.held}


#: An option whose FE correction stopped at the held first step is completed where its
#: BIC lies within this much (plus 4 times the last FE step's change of the model it
#: extends) of the best option's or of being decisive.  The completing FE step moved
#: chi^2 by 0.07-3.3 on three mode-1 curves (28 November 2026): an option further off
#: cannot become the choice, nor decisive, and is reported held (no FE step of its own).
FINISH_MARGIN_BIC = 10.0


def _finish_options(fitter, current, models, options, settings) -> None:
    """Complete the FE correction of the held options that could matter (in place)."""
    chi2 = (current.correction or {}).get("chi2") or [0.0, 0.0]
    margin = FINISH_MARGIN_BIC + 4.0 * abs(chi2[-1] - chi2[-2])
    while True:
        best = min(o["bic"] for o in options)
        near = [k for k, m in enumerate(models) if m.held and (
            options[k]["bic"] - best < margin
            or options[k]["delta_bic"] <= settings.delta_bic + margin)]
        if not near:
            return
        for k in near:
            models[k] = fitter.fit(models[k].effects)
            options[k] = _option(models[k], current, settings)


def select_effects(fitter: EffectFitter, settings) -> dict:
    """Forward selection of the effects, then the check of each against the final model.

    Parameters
    ----------
    fitter : EffectFitter
    settings : Settings
        ``alpha``, ``delta_bic`` and ``ambiguity_bic`` are used.

    Returns
    -------
    dict
        ``base`` and ``final`` (:class:`TimeModel`), ``chain`` (the models of
        the steps taken, base first), ``steps`` (JSON-able: per step, every
        option with its chi^2, BIC and ΔBIC against the model it extends, the
        effect added or None, the tied effects), ``removed`` (effects the final
        check dropped, with their ΔBIC), ``fitted`` (every model fitted by name).
    """
    base = fitter.fit(())
    current, chain, steps = base, [base], []
    while True:
        addable = fitter.addable(current.effects)
        if not addable:
            break
        if current.misfit_p >= settings.alpha:
            # nothing to explain: no option can be decisive; creep alone is fitted
            # for the report (what it would change), nothing else is
            addable = [e for e in addable if e == VISCOELASTIC_CREEP and not current.effects]
            if not addable:
                break
        models = [fitter.fit(current.effects + (e,), finish=False) for e in addable]
        options = [_option(m, current, settings) for m in models]
        _finish_options(fitter, current, models, options, settings)
        k = int(np.argmin([o["bic"] for o in options]))
        best, chosen = models[k], options[k]
        tied = [o["effects"][-1] for o in options
                if o is not chosen and o["decisive"]
                and o["bic"] - chosen["bic"] < settings.ambiguity_bic]
        steps.append({"step": len(steps) + 1, "from": current.name,
                      "from_misfit_p": current.misfit_p, "options": options,
                      "added": chosen["effects"][-1] if chosen["decisive"] else None,
                      "ambiguous_with": tied if chosen["decisive"] else []})
        if not chosen["decisive"]:
            break
        current = best
        chain.append(best)
    removed = []
    final = chain[-1]
    for e in list(final.effects) if len(final.effects) > 1 else []:
        if e not in final.effects:
            continue
        drop = {e, CREEP_SECOND_TERM} if e == VISCOELASTIC_CREEP else {e}
        without = fitter.fit(tuple(x for x in final.effects if x not in drop))
        d = final.bic - without.bic
        if d > settings.delta_bic:
            removed.append({"effect": e, "delta_bic_without": float(d)})
            final = without
    if removed:
        chain.append(final)
    return {"base": base, "final": final, "chain": chain, "steps": steps, "removed": removed,
            "fitted": {m.name: m for m in fitter._cache.values()}}
