"""The paper's reproduction: what only its figures and tables need.

The identification studies of the paper (sections 3.2-3.3) on the test point
of the configuration (``identification.target``; the paper's X1d = 0.0055,
X1h = 0.00041 MPa), apart from the library that users call
(:mod:`skinsuction.identify`, :mod:`skinsuction.diagnose`):

* ``_setup``: the test curves in two variants (:data:`SOURCES`: a direct FE
  run, and the curve taken from the interpolated space, the paper's variant),
  the spaces and the objectives (:class:`StudySetup`);
* ``_runs``: Figure 4 (:func:`single_probe_study`), Figure 4b
  (:func:`cost_landscape`), Figure 7 (:func:`alpha_sweep`), Figure 8
  (:func:`ratio_study`), their summaries, and the same runs on two spaces
  (:func:`compare_spaces`);
* ``_timing``: time per identification (:func:`timing_study`) and window
  focusing against scipy's optimisers and the FE model in the loop
  (:func:`optimiser_comparison`, :func:`fe_in_the_loop`);
* ``_figures``: the ``build_*`` function of every figure and table rule.

An identification *succeeds* if both moduli are within ``success_tolerance``
(default 1 %) of the truth.

Examples
--------
>>> from skinsuction.identify import analytic_surrogate_space
>>> from skinsuction.space import evaluate
>>> target = (0.0055, 0.00041)
>>> spaces = {p: analytic_surrogate_space(p) for p in (2.0, 6.0)}
>>> curves = {"space": {p: (s.pressure_mbar, evaluate(s, [target])[0])
...                     for p, s in spaces.items()}}
>>> setup = StudySetup(spaces, curves, target)
>>> runs = single_probe_study(setup, repeats=3, seed=0, sources=["space"])
>>> summary = summarise_runs(runs, target, ["source", "objective"])
>>> summary[["objective", "success_fraction"]].values.tolist()
[['single_2mm', 1.0], ['single_6mm', 1.0]]
"""

from ._figures import (
    build_comparison,
    build_fig4,
    build_fig4b,
    build_fig5,
    build_fig6,
    build_fig7,
    build_fig8,
    build_timing,
    curves_fig8,
    identify_runs,
    table_fig4,
    table_fig6,
    table_fig7,
)
from ._runs import (
    RUN_STUDIES,
    alpha_sweep,
    alpha_threshold,
    compare_spaces,
    cost_landscape,
    landscape_summary,
    ratio_study,
    runs_frame,
    single_probe_study,
    summarise_runs,
    write_runs,
    write_space_comparison,
)
from ._setup import (
    OBJECTIVES,
    PAPER_TIMING,
    PAPER_WINDOW_FOCUSING,
    SOURCES,
    StudySetup,
    build_objective,
    case_seed,
    load_setup,
    load_spaces,
    make_test_curves,
    read_test_curves,
    scale_free_setup,
    setup_from_files,
    target_of,
)
from ._timing import (
    fe_in_the_loop,
    optimiser_comparison,
    reference_minimum,
    timing_study,
    write_fe_in_the_loop,
)

__all__ = [
    "OBJECTIVES", "PAPER_TIMING", "PAPER_WINDOW_FOCUSING", "SOURCES", "RUN_STUDIES",
    "StudySetup", "build_objective", "case_seed", "load_setup", "load_spaces",
    "make_test_curves", "read_test_curves", "scale_free_setup", "setup_from_files", "target_of",
    "alpha_sweep", "alpha_threshold", "compare_spaces", "cost_landscape", "landscape_summary",
    "ratio_study", "runs_frame", "single_probe_study", "summarise_runs", "write_runs",
    "write_space_comparison",
    "fe_in_the_loop", "optimiser_comparison", "reference_minimum", "timing_study",
    "write_fe_in_the_loop",
    "build_comparison", "build_fig4", "build_fig4b", "build_fig5", "build_fig6", "build_fig7",
    "build_fig8", "build_timing", "curves_fig8", "identify_runs", "table_fig4", "table_fig6",
    "table_fig7",
]
