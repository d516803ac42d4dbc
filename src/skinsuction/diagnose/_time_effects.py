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
           "cycle_pattern", "physical_effects", "layer_test"]

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


class EffectFitter:
    """Fits (and caches) the model of any set of effects on prepared time curves.

    Parameters
    ----------
    prep : dict
        :func:`skinsuction.identify.time_curves.prepare_time_fit`'s output.
    settings : Settings
    causes : list of str
        The elastic causes tried (their rays: ``prep["space"].cause_rays``).

    With ``settings.fe_correction`` steps, every fit with creep is corrected by FE
    time solves at the fit (:func:`skinsuction.identify.fe_corrected_fit`); an
    elastic fit needs none (the fast path is then the rays themselves).
    """

    def __init__(self, prep: dict, settings, causes):
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

    def fit(self, effects) -> TimeModel:
        """The model of ``effects`` (cached by set: the order only names it)."""
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
        model = self._cache[key]
        if model.effects != tuple(effects):  # the same fit, named in this order
            model = dataclasses.replace(model, effects=tuple(effects))
        return model

    def _corrected_parent(self, key):
        """The most specific model nested in ``key`` corrected by FE time solves, or None."""
        nested = [m for m in self._cache.values()
                  if set(m.effects) < set(key) and (m.correction or {}).get("applied")]
        return max(nested, key=lambda m: len(m.effects), default=None)

    def _corrected(self, fit, rays, cause, key, data=None, layers=False, warm=None):
        """The fit corrected by FE time solves; the fast fit, said so, if one stops.

        ``warm``, a corrected model nested in this one: its fast-path error, measured
        at a skin near this fit, is held for the first step (a fit without an FE
        solve), so a model that adds an effect to a corrected one pays for one FE
        solve per curve fewer."""
        from skinsuction.identify import fe_corrected_fit, fit_time_model, time_fit_skin

        c = rays[self.probes[0]].cause if cause is not None else None
        geometry, bottom = self.prep["geometry"], self.prep["space"].bottom

        def skin_of(parameters):
            return time_fit_skin(parameters, geometry, bottom, c)

        data = self.data if data is None else data
        steps, fast_chi2 = int(self.settings.fe_correction), float(fit.chi2)
        warm = warm if steps > 1 and warm is not None and warm.data is not None else None
        try:
            if warm is not None:
                fit = fit_time_model(rays, warm.data, terms=fit.terms, seed=self._seed_of(key),
                                     repeats=0, starts=[fit.theta], layers=layers)
            fit, corrected, record = fe_corrected_fit(
                rays, data, fit, skin_of, iterations=steps - (warm is not None),
                seed=self._seed_of(key), layers=layers)
            if warm is not None:
                record = {**record, "iterations": steps, "warm_start": warm.name,
                          "chi2": [fast_chi2, *record["chi2"]]}
            return fit, corrected, record
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
            "fe_correction_from": corr.get("warm_start")}


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
        models = [fitter.fit(current.effects + (e,)) for e in addable]
        options = [_option(m, current, settings) for m in models]
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


def cycle_pattern(data, fitted, sd_factor: float = 3.0) -> list:
    """Words for a first cycle that departs from the later ones (preconditioning).

    Per curve with two or more holds (``on`` phases), the mean residual of each
    hold; the first departs when it differs from the later holds' mean by more
    than ``sd_factor`` times the spread of the later holds (or their standard
    error, whichever is larger) and by more than the noise sd.

    Parameters
    ----------
    data : list of TimeFitData
    fitted : list of ndarray
        The final model's deflections (mm) per curve.

    Returns
    -------
    list of str
    """
    out = []
    for d, m in zip(data, fitted):
        on = np.concatenate([[False], d.phase == "on", [False]]).astype(int)
        edges = np.flatnonzero(np.diff(on))
        holds = list(zip(edges[0::2], edges[1::2]))
        if len(holds) < 2:
            continue
        r = 1e3 * (d.deflection_mm - np.asarray(m, dtype=float))
        means = np.array([np.mean(r[a:b]) for a, b in holds])
        later = means[1:]
        se = float(np.mean([np.std(r[a:b]) / math.sqrt(max(b - a, 1)) for a, b in holds[1:]]))
        spread = float(np.std(later)) if later.size > 1 else 0.0
        gap = float(means[0] - later.mean())
        if abs(gap) > sd_factor * max(spread, se) and abs(gap) > 1e3 * d.noise_sd_mm:
            out.append(f"{d.label}: the first cycle departs from the later ones by "
                       f"{gap:+.1f} µm in its hold (the later holds agree within "
                       f"{max(spread, se):.1f} µm): the skin changes over the first cycle "
                       "(preconditioning), which no model here holds")
    return out


#: How much more one layer's g must be than the other's to name that layer alone.
LAYER_RATIO = 3.0


def _creeping(iv: dict, decisive: bool) -> str:
    """The layer test's answer from the per-layer g intervals.

    ``"dermis"`` or ``"hypodermis"``: the spectra differ (``decisive``), that layer's g
    exceeds 0.05 at its lower end (or its estimate is at the spectrum's upper edge) and
    the other's estimate by :data:`LAYER_RATIO`; ``"both"``: both g's lower ends exceed
    0.05; else ``"cannot tell"``.

    >>> iv = lambda e, lo, hi, up=False: {"estimate": e, "lower": lo, "upper": hi,
    ...                                   "upper_open": up}
    >>> _creeping({"g_dermis": iv(0.03, 0.001, 0.8), "g_hypodermis": iv(5, 0.001, 5, True)},
    ...           True)
    'hypodermis'
    >>> _creeping({"g_dermis": iv(0.4, 0.2, 0.6), "g_hypodermis": iv(0.5, 0.3, 0.8)}, True)
    'both'
    >>> _creeping({"g_dermis": iv(0.03, 0.001, 0.8), "g_hypodermis": iv(5, 0.001, 5, True)},
    ...           False)
    'cannot tell'
    """
    gd, gh = iv["g_dermis"], iv["g_hypodermis"]

    def creeps(g):
        return g["lower"] > 0.05 or (g.get("upper_open") and g["estimate"] > 0.05)

    for name, g, other in (("dermis", gd, gh), ("hypodermis", gh, gd)):
        if decisive and creeps(g) and g["estimate"] > LAYER_RATIO * other["estimate"]:
            return name
    if gd["lower"] > 0.05 and gh["lower"] > 0.05:
        return "both"
    return "cannot tell"


def layer_test(fitter: EffectFitter, final: TimeModel, settings) -> dict:
    """Which layer creeps: the final model's spectrum shared by both layers against one
    spectrum per layer (one term each).  With ``settings.fe_correction`` each fit is
    corrected by FE time solves with a spectrum per layer and held to the data's own
    model error; without, both are under the per-layer fast path's larger model error
    (:data:`skinsuction.identify.MODEL_ERROR_LAYERS`: a screen).

    Two probes of different apertures are needed: a small one sees mostly the dermis, a
    large one the hypodermis too (the hypodermis's share of the compliance, ``beta``,
    is reported per probe).  With one aperture the test is not run, and says why.

    Parameters
    ----------
    fitter : EffectFitter
    final : TimeModel
        The selection's final model; it must hold creep.
    settings : Settings

    Returns
    -------
    dict
        ``tested`` (bool), ``reason``; when tested: ``delta_bic`` (per layer minus
        shared), ``decisive`` (the spectra differ), ``creeping`` (:func:`_creeping`),
        ``elastic_check`` (does the final model's elastic effect still earn its place
        with a spectrum per layer?), the per-layer ``parameters`` and ``intervals``,
        ``beta`` per probe, ``model_error``, ``fe_correction`` (per fit).
    """
    from skinsuction.identify import (MODEL_ERROR_LAYERS, TimeCurveModel, fit_data_of,
                                      fit_time_model, laplace_intervals)

    if VISCOELASTIC_CREEP not in final.effects:
        return {"tested": False, "reason": "no creep named"}
    if len({d.probe_mm for d in fitter.data}) < 2:
        return {"tested": False,
                "reason": "one probe cannot tell which layer creeps: its curve sees one "
                          "mix of the layers (measure a second aperture, e.g. 2 + 8 mm)"}
    corrected = bool(settings.fe_correction)
    # corrected by FE time solves, the per-layer model is held to the data's own model
    # error; the fast path alone needs its larger one
    data = (fitter.data if corrected else
            [fit_data_of(c, noise_sd_mm=d.noise_sd_mm, model_error=MODEL_ERROR_LAYERS)
             for c, d in zip(fitter.prep["curves"], fitter.data)])
    rays = final.rays
    cause = final.elastic_cause
    k0 = 2 + (cause is not None)
    theta = np.asarray(final.fit.theta, dtype=float)
    start = theta[:k0 + 2]  # the first (fastest) creep term of the final model
    seed = np.random.SeedSequence(int(settings.seed), spawn_key=(99,))
    s_shared, s_layers = seed.spawn(2)
    records = {}

    def fit(name, rays_, start_, seed_, per_layer, cause_):
        f = fit_time_model(rays_, data, terms=1, seed=seed_, repeats=settings.repeats,
                           starts=[start_], layers=per_layer)
        if not corrected:
            return f, data
        key = (VISCOELASTIC_CREEP,) + ((cause_,) if cause_ else ())
        f, fd, records[name] = fitter._corrected(f, rays_, cause_, key, data, per_layer)
        return f, fd

    shared, _ = fit("shared", rays, start, s_shared, False, cause)
    layered_start = np.concatenate([shared.theta, shared.theta[k0:k0 + 2]])
    layers, layers_data = fit("per_layer", rays, layered_start, s_layers, True, cause)
    b_shared = bic(shared.chi2, shared.n_params, shared.n_points)
    b_layers = bic(layers.chi2, layers.n_params, layers.n_points)
    delta = float(b_layers - b_shared)
    iv = laplace_intervals(rays, layers_data, layers, level=settings.level)
    p = layers.parameters
    model = TimeCurveModel(rays, data, 1, layers=True)
    beta = {f"{d.probe_mm:g}": float(model.hypodermis_share(layers.theta[None], d.probe_mm,
                                                            float(d.pressure_mbar.max()))[0])
            for d in data}
    decisive = bool(delta <= settings.delta_bic)  # the layers' spectra differ
    creeping = _creeping(iv, decisive)
    # does the elastic effect still earn its place once each layer has its spectrum?
    elastic_check = None
    if decisive and cause is not None:
        plain, _ = fit("without_elastic_effect", fitter.rays[None], np.delete(layers.theta, 2),
                       seed.spawn(1)[0], True, None)
        d_plain = float(b_layers - bic(plain.chi2, plain.n_params, plain.n_points))
        elastic_check = {"effect": cause, "delta_bic_without": d_plain,
                         "earns_its_place": bool(d_plain <= settings.delta_bic),
                         "without_it": {"chi2": float(plain.chi2),
                                        "parameters": plain.parameters}}
    return {"tested": True, "delta_bic": delta, "decisive": decisive, "creeping": creeping,
            "elastic_check": elastic_check,
            "parameters": {k: p[k] for k in ("g_dermis", "tau_s_dermis", "g_hypodermis",
                                             "tau_s_hypodermis")},
            "intervals": {k: iv[k] for k in ("g_dermis", "tau_dermis", "g_hypodermis",
                                             "tau_hypodermis")},
            "shared": {"chi2": float(shared.chi2), "bic": float(b_shared),
                       "parameters": shared.parameters},
            "chi2": float(layers.chi2), "bic": float(b_layers), "beta": beta,
            "model_error": (dict(data[0].model_error) if corrected
                            else dict(MODEL_ERROR_LAYERS)),
            "fe_correction": records or None,
            "reason": ("a spectrum per layer against one for both, each fit corrected by FE "
                       "time solves (docs/effects.md)" if corrected else
                       "a spectrum per layer against one for both, each under the per-layer "
                       "fast path's model error (2 % of the curve; docs/effects.md)")}
