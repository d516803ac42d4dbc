"""Identification of the dermis and hypodermis moduli from suction curves.

Paper sections 2.3-2.4 and 3.2-3.3: a measured curve M(p) is compared with the
simulated space Omega_s(X1d, X1h, p), interpolated off the grid by cubic
Lagrange interpolation, through a cost function (single probe, weighted or
ratio of the 2 mm and 6 mm probes) that the window focusing stochastic
algorithm minimises.

Every fit of the package (the ramps here, the time curves, each model of
:mod:`skinsuction.diagnose`) runs on one fitting engine (:mod:`._engine`):
:func:`focus` (a window focusing run), :func:`polish` (bounded least squares from
a point), :func:`repeated_fit` (runs from seeds and given starts, the best
polished: a :class:`FitResult`) and :func:`profile_intervals`, on any
:class:`Objective` (a :class:`Chi2Objective` for a fit in units of the noise).

``skinsuction identify`` returns an :class:`Identification` (a pressure ramp,
:func:`skinsuction.identify.measured_fit.identify_data`) or a
:class:`TimeIdentification` (time curves,
:func:`skinsuction.identify.time_curves.identify_time_data`): named fields, and
``to_json()`` the content of ``identification.json``, both written by
:func:`write_identification`.

Examples
--------
>>> from skinsuction.identify import analytic_surrogate_space, single_objective, window_focusing
>>> from skinsuction.space import evaluate
>>> s6 = analytic_surrogate_space(6.0)          # stands in for the FE space
>>> curve = (s6.pressure_mbar, evaluate(s6, [[0.0055, 0.00041]])[0])
>>> result = window_focusing(single_objective(s6, curve), seed=0)
>>> result.estimate.round(6).tolist(), result.E_um < 1e-3
([0.0055, 0.00041], True)
"""

from ._bounds import BOUND_FRACTION, bound_flags
from ._engine import (
    POLISH,
    Chi2Objective,
    FitResult,
    Objective,
    Polished,
    RepeatedIdentification,
    focus,
    identify_repeated,
    polish,
    polish_run,
    repeated_fit,
)
from ._identification import Identification, TimeIdentification, write_identification
from ._intervals import (
    Interval,
    LikelihoodIntervals,
    interval_threshold,
    misfit_scale,
    profile_intervals,
)
from ._objectives import (
    RatioObjective,
    SingleObjective,
    WeightedObjective,
    correlation_error,
    cost,
    ratio_objective,
    single_objective,
    weighted_objective,
)
from ._surrogate import (
    PAPER_PRESSURE_MBAR,
    PAPER_X1D,
    PAPER_X1H,
    analytic_surrogate_space,
    surrogate_curve,
    surrogate_deflection,
    write_surrogate_space,
)
from ._time_correction import FittedTimeModel, fe_corrected_fit, fe_time_curve, time_fit_skin
from ._time_fit import (MODEL_ERROR_LAYERS, RELEASE_S, TimeCurveModel, TimeFit, TimeFitData,
                        evaluate_time_fit, fit_data_of, fit_time_model, time_fit_data)
from ._time_intervals import laplace_intervals, time_bound_flags
from ._window_focusing import (
    IdentificationError,
    IterationState,
    WindowFocusingResult,
    samples_for,
    window_focusing,
)

__all__ = [
    "Identification",
    "TimeIdentification",
    "write_identification",
    "bound_flags",
    "Objective",
    "Chi2Objective",
    "focus",
    "polish",
    "polish_run",
    "Polished",
    "POLISH",
    "repeated_fit",
    "FitResult",
    "Interval",
    "LikelihoodIntervals",
    "interval_threshold",
    "misfit_scale",
    "profile_intervals",
    "TimeFit",
    "TimeFitData",
    "fit_time_model",
    "fe_corrected_fit",
    "FittedTimeModel",
    "fe_time_curve",
    "time_fit_skin",
    "TimeCurveModel",
    "MODEL_ERROR_LAYERS",
    "fit_data_of",
    "time_fit_data",
    "RELEASE_S",
    "evaluate_time_fit",
    "laplace_intervals",
    "time_bound_flags",
    "BOUND_FRACTION",
    "cost",
    "correlation_error",
    "SingleObjective",
    "WeightedObjective",
    "RatioObjective",
    "single_objective",
    "weighted_objective",
    "ratio_objective",
    "window_focusing",
    "identify_repeated",
    "samples_for",
    "IdentificationError",
    "IterationState",
    "WindowFocusingResult",
    "RepeatedIdentification",
    "PAPER_X1D",
    "PAPER_X1H",
    "PAPER_PRESSURE_MBAR",
    "surrogate_deflection",
    "analytic_surrogate_space",
    "surrogate_curve",
    "write_surrogate_space",
]
