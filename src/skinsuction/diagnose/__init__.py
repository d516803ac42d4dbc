"""Diagnosis of measured suction curves: what the neo-Hookean model gets wrong and why.

``skinsuction diagnose MEASURED.csv --out DIR`` (:func:`command`):

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
                  "systematic_misfit", "description"},
     "candidates": [{"cause", "parameters", "E_um", "delta_bic", "holdout_E_um"}],
     "cause": "none" | "beyond_space" | <cause>,
     "verdict": "neo_hookean_fits" | "cause_found" | "unexplained_misfit" | "beyond_space",
     "beyond_space": [{"model", "parameter", "side", "edge", "config_key", "value"}],
     "extended": {...} | null, "gain": {...} | null}

Parameters are in MPa (moduli), mm (thickness), 1 (lambda0); E is eq. 7 of the
paper in µm on the concatenated fitted points.  See :mod:`._rays` for the ray
spaces, :mod:`._stats` for the statistics and :mod:`._diagnose` for the rule.
"""

from skinsuction.space import BASELINE, DEFAULT_CAUSES, NONE, Cause, default_registry, registry_from_config
from ._cli import add_arguments, command
from ._diagnose import Settings, diagnose, diagnose_file, prepare_data
from ._fit import Fit, FitData, ModelCurves, fit_model
from ._report import write_report
from ._stats import bic, misfit_test, noise_from_differences, noise_from_replicates
from ._virtual import (
    DETECTABLE_EFFECTS,
    DRAW_RANGES,
    VirtualExperiment,
    draw_experiment,
    virtual_experiment,
    write_csv,
)

__all__ = [
    "BASELINE", "NONE", "Cause", "DEFAULT_CAUSES", "default_registry", "registry_from_config",
    "add_arguments", "command",
    "Settings", "diagnose", "diagnose_file", "prepare_data",
    "Fit", "FitData", "ModelCurves", "fit_model",
    "write_report",
    "bic", "misfit_test", "noise_from_differences", "noise_from_replicates",
    "DETECTABLE_EFFECTS", "DRAW_RANGES", "VirtualExperiment", "draw_experiment",
    "virtual_experiment", "write_csv",
]
