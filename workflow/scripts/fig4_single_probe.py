"""Rule fig4_single_probe: Figure 4 and its table."""

import os

# One BLAS/OpenMP thread (before NumPy is imported): jobs run side by side, and the
# timings are single-thread timings.
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ[_var] = "1"

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
    from skinsuction.figures.fig4 import build_fig4

    t = snakemake.params.target
    build_fig4(
        snakemake.input.runs,
        png=snakemake.output.png,
        pdf=snakemake.output.pdf,
        csv=snakemake.output.table,
        target=(t["x1d"], t["x1h"]),
        success_tolerance=snakemake.params.success_tolerance,
    )
