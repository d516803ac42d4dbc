"""Diagnosis of measured suction curves: what the neo-Hookean model gets wrong and why.

``skinsuction diagnose MEASURED.csv --out DIR`` (:mod:`skinsuction.commands.diagnose`):

1. fits the two-layer neo-Hookean model (both probes jointly when both are
   present) on the neo-Hookean scale-free space;
2. tests its residuals for a systematic (smooth) pattern against the noise,
   estimated from replicates or from the data, and describes the pattern;
3. fits each candidate cause of the registry (strain stiffening, dermis
   thickness, pre-tension, ...: one extra parameter each) on its extended ray
   space, with E, delta BIC and a cross-probe holdout;
4. names the cause whose gain is decisive and that removes the misfit, or
   ``none``; where the fit it stands on sits at an edge of the simulated space
   the verdict is ``beyond_space`` (never ``none``), naming the parameter and
   the configuration key that widens the space;
5. writes ``DIR/report.json``, ``DIR/report.md`` and figures.

``report.json`` (other keys are added)::

    {"input": {"file", "sha256", "probes_mm"}, "noise_um",
     "baseline": {"model": "neo_hookean", "parameters": {"X1d", "X1h"}, "E_um",
                  "systematic_misfit", "description", "skin"},
     "candidates": [{"cause", "parameters", "E_um", "delta_bic", "holdout_E_um", "skin"}],
     "cause": "none" | "beyond_space" | <cause>,
     "verdict": "neo_hookean_fits" | "cause_found" | "unexplained_misfit" | "beyond_space",
     "beyond_space": [{"model", "parameter", "side", "edge", "config_key", "value"}],
     "extended": {...} | null, "gain": {...} | null}

Every fit records the skin it describes (``"skin"``, :meth:`skinsuction.model.Skin.to_dict`),
which :meth:`~skinsuction.model.Skin.from_dict` reads back.
Parameters are in MPa (moduli), mm (thickness), 1 (lambda0); E is eq. 7 of the
paper in µm on the concatenated fitted points.  See :mod:`skinsuction.space` for the
ray spaces, :mod:`._stats` for the statistics, :mod:`._steps` for the steps and
:mod:`._rule` for the rule.
How well the rule does (virtual experiments, confusion rates, the space's accuracy)
is studied in :mod:`skinsuction.evaluation`, which this package does not import.
"""

from skinsuction.space import BASELINE, DEFAULT_CAUSES, NONE, Cause, default_registry, registry_from_config
from ._data import prepare_data
from ._diagnose import diagnose, diagnose_file
from ._rule import decide
from ._settings import Settings
from ._steps import BeyondSpaceError
from ._window import fit_in_window, ratio_window
from ._fit import (Fit, FitData, ModelCurves, fit_intervals, fit_model, nested_start,
                   with_space_error)
from ._report import write_report
from ._stats import bic, misfit_test, noise_from_differences, noise_from_replicates
from ._time import VISCOELASTIC_CREEP, diagnose_time_data, diagnose_time_file, write_time_report
from ._time_effects import CREEP_SECOND_TERM, EffectFitter, select_effects
from ._time_layers import layer_test

__all__ = [
    "BASELINE", "NONE", "Cause", "DEFAULT_CAUSES", "default_registry", "registry_from_config",
    "Settings", "diagnose", "diagnose_file", "prepare_data",
    "BeyondSpaceError", "decide", "fit_in_window", "ratio_window",
    "Fit", "FitData", "ModelCurves", "fit_intervals", "fit_model", "nested_start",
    "with_space_error",
    "write_report",
    "bic", "misfit_test", "noise_from_differences", "noise_from_replicates",
    "VISCOELASTIC_CREEP", "diagnose_time_data", "diagnose_time_file", "write_time_report",
    # time curves, effect by effect
    "CREEP_SECOND_TERM", "EffectFitter", "select_effects", "layer_test",
]
