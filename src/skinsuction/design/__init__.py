"""Plan the measurement: which probes, suction and layers answer the study's question.

Before anyone is measured: for a box of plausible skins (a cohort's ranges) or a
study's table, and candidate designs (probe sets from 2, 4, 6 and 8 mm, a ramp
to 100-500 mbar, the noise and the 0.01 mm resolution, which thicknesses are
given), :func:`run_design` predicts from the simulated spaces, without FE runs:

* the 95 % interval of X1d and X1h (median and upper quantile of its relative
  half-width over the skins) and the fraction of skins where it is bounded;
* each cause's detectable fraction, and each pair's attribution ceiling;
* for mode 1 and mode 2 designs (the Cutometer's time curves), the intervals of the
  long-time moduli and of a one-term relaxation spectrum (g, tau);

and recommends the design with the fewest probes, then the lowest suction, that
meets the :class:`Question` (or says that none does, and offers the best).

The predictions are profile-likelihood intervals on the noise-free curves: the
expected chi^2 surface of a noisy measurement.  ``tests/test_design.py`` checks
them against realised fits of noisy curves.

Examples
--------
The paper's finding (its Figure 4) before measuring: the 2 mm probe alone leaves
X1h open, the 2 + 6 mm pair bounds it:

>>> from skinsuction.design import Box, Question, designs_from, predict_designs
>>> from skinsuction.diagnose import Settings
>>> from skinsuction.space import SHIPPED_SPACE_DIR, read_ray_spaces
>>> skins = Box(x1d_mpa=0.05, x1h_ratio=0.02).draw(1, seed=0)
>>> rows = predict_designs(skins, designs_from(["2", "2+6"], [100]), progress=False,
...                        spaces=read_ray_spaces(SHIPPED_SPACE_DIR), settings=Settings())
>>> rows["X1h_bounded"].tolist()
[False, True]
"""

from ._box import CAUSE_COLUMNS, Box, Design, Question, designs_from, skins_from_table
from ._check import (CHECK_CAUSES, check_skin, check_summary, measure_skin, parse_design,
                     repredict)
from ._box import relative_halfwidth
from ._predict import predict_skin
from ._predict_time import predict_time, time_curves
from ._run import predict_designs, run_design
from ._summary import design_markdown, recommend, summarize

__all__ = ["Box", "Design", "Question", "designs_from", "skins_from_table", "CAUSE_COLUMNS",
           "predict_skin", "relative_halfwidth", "predict_designs", "run_design",
           "summarize", "recommend", "design_markdown", "CHECK_CAUSES", "check_skin",
           "check_summary", "measure_skin", "parse_design", "repredict", "predict_time",
           "time_curves"]
