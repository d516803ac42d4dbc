"""Rule fig8_ratio: Figure 8 and its tables."""

import os

# One BLAS/OpenMP thread (before NumPy is imported): jobs run side by side, and the
# timings are single-thread timings.
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ[_var] = "1"

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
    from skinsuction.figures.fig8 import build_fig8

    build_fig8(
        snakemake.input.space,
        snakemake.input.curves,
        snakemake.input.runs,
        png=snakemake.output.png,
        pdf=snakemake.output.pdf,
        csv=snakemake.output.table,
        curves_csv=snakemake.output.ratio_curves,
        settings=dict(snakemake.params.settings),
    )
