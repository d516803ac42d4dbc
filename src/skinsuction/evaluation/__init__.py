"""The study of the method, not the method: how well identification and diagnosis do.

:mod:`skinsuction.identify` and :mod:`skinsuction.diagnose` are the method, what a
user runs on a measured curve.  This package measures them on curves whose truth
is known, and neither of them imports it (tests/test_layers.py):

* virtual experiments: direct FE curves with a hidden effect and noise
  (:func:`virtual_experiment`, :func:`draw_experiment`, :func:`write_csv`), and
  viscoelastic time curves (:func:`virtual_curve`, :func:`write_time_csv`);
* the diagnosis over the physiological domain: one diagnosed draw
  (:func:`run_draw`, :func:`run_draws`) and the confusion matrices and rates over
  the draws (:func:`summarise`, :func:`attribution_ceiling`);
* the accuracy of the scale-free space against direct FE runs
  (:func:`draw_points`, :func:`compare_point`), and direct FE runs at the
  parameters a diagnosis identified (:func:`fe_check`, Figure 6);
* the classical optimisers the window focusing is compared with
  (:func:`least_squares_from_random_starts`, :func:`differential_evolution_fit`);
* which skins reach the published Cutometer values of the face, creep alone or
  creep with stiffening (:func:`published_ranges_study`);
* a synthetic clinical study of subjects with their own layers, ramps and mode-1
  curves, and its check against the truth (:func:`make_layers_study`,
  :func:`layers_study_check`);
* the shipped synthetic example, remade with ``python -m skinsuction.evaluation.example``
  (:mod:`skinsuction.evaluation.example`, not imported here).

It sits in the layer of :mod:`skinsuction.paper` and :mod:`skinsuction.cohort`: it
may import identify and diagnose, only through their public names.

Examples
--------
>>> from skinsuction.evaluation import attribution_ceiling
>>> attribution_ceiling([0.0, 4.0]).round(3)
array([0.5  , 0.841])
"""

from ._accuracy import (
    ABS_TARGET_UM,
    PROTOCOLS,
    REL_TARGET,
    AccuracyPoint,
    compare_point,
    draw_points,
    normalised_error,
)
from ._baselines import BaselineResult, differential_evolution_fit, least_squares_from_random_starts
from ._check import fe_check, models_of_figure6
from ._confusion import (
    WIDE_DOMAIN,
    domain_from_config,
    draw_wide,
    given_keywords,
    initial_stress_kpa,
    interval_columns,
    run_draw,
    run_draws,
)
from ._solvers import OTHER_SOLVERS, SolverRefused, solver_curves
from ._effects import (
    EFFECT_CLASSES,
    EFFECT_DESIGNS,
    diagnose_effect_draw,
    draw_effects,
    effects_confusion_markdown,
    effects_confusion_study,
    effects_confusion_summary,
    effects_skin,
)
from ._ramp_effects import (
    RAMP_CLASSES,
    RAMP_DESIGNS,
    diagnose_ramp_draw,
    draw_ramp_effects,
    ramp_effects_markdown,
    ramp_effects_study,
    ramp_effects_summary,
)
from ._published import (
    FACE_PROTOCOL,
    PUBLISHED_FACE,
    box_distance,
    closest_skin,
    evaluate_draw,
    published_ranges_markdown,
    published_ranges_study,
    published_ranges_summary,
)
from ._rates import (UNDIAGNOSED, attribution_ceiling, interval_coverage, summarise, under_rule,
                     wrong_untied)
from ._layers_study import (
    LayersStudyDesign,
    draw_layers_subject,
    layers_study_check,
    layers_study_markdown,
    make_layers_study,
)
from ._time_virtual import (
    mode1_suction,
    mode2_suction,
    virtual_curve,
    virtual_skin_curve,
    write_time_csv,
)
from ._virtual import (
    DETECTABLE_EFFECTS,
    DRAW_RANGES,
    VirtualExperiment,
    draw_experiment,
    virtual_experiment,
    write_csv,
)

__all__ = [
    # virtual experiments
    "VirtualExperiment", "virtual_experiment", "draw_experiment", "write_csv",
    "DRAW_RANGES", "DETECTABLE_EFFECTS",
    "mode1_suction", "mode2_suction", "virtual_curve", "virtual_skin_curve", "write_time_csv",
    # a synthetic study of subjects with their own layers
    "LayersStudyDesign", "draw_layers_subject", "make_layers_study", "layers_study_check",
    "layers_study_markdown",
    # the published Cutometer values: creep alone, or with stiffening
    "PUBLISHED_FACE", "FACE_PROTOCOL", "box_distance", "evaluate_draw", "closest_skin",
    "published_ranges_study", "published_ranges_summary", "published_ranges_markdown",
    # single and paired effects in time curves
    "EFFECT_CLASSES", "EFFECT_DESIGNS", "draw_effects", "effects_skin", "diagnose_effect_draw",
    "effects_confusion_study", "effects_confusion_summary", "effects_confusion_markdown",
    # single and paired effects in ramps
    "RAMP_CLASSES", "RAMP_DESIGNS", "draw_ramp_effects", "diagnose_ramp_draw",
    "ramp_effects_study", "ramp_effects_summary", "ramp_effects_markdown",
    # the diagnosis over the physiological domain
    "WIDE_DOMAIN", "draw_wide", "domain_from_config", "given_keywords", "initial_stress_kpa",
    "run_draw", "run_draws", "interval_columns",
    "UNDIAGNOSED", "under_rule", "summarise", "attribution_ceiling", "wrong_untied",
    "interval_coverage",
    # virtual experiments from other discretisations and FE codes
    "OTHER_SOLVERS", "SolverRefused", "solver_curves",
    # accuracy of the space, FE checks of a diagnosis
    "AccuracyPoint", "draw_points", "compare_point", "normalised_error",
    "REL_TARGET", "ABS_TARGET_UM", "PROTOCOLS",
    "fe_check", "models_of_figure6",
    # baselines of the identification
    "BaselineResult", "least_squares_from_random_starts", "differential_evolution_fit",
]
