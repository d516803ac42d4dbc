"""Rule fig4b_cost_landscape: Figure 4b (cost landscapes), its table and data."""

import os

# One BLAS/OpenMP thread (before NumPy is imported): jobs run side by side, and the
# timings are single-thread timings.
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ[_var] = "1"

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
    from skinsuction.figures.fig4b import build_fig4b

    settings = dict(snakemake.params.settings)
    build_fig4b(
        snakemake.input.space,
        snakemake.input.curves,
        png=snakemake.output.png,
        pdf=snakemake.output.pdf,
        csv=snakemake.output.table,
        landscape_out=snakemake.output.landscape,
        settings=settings,
        points=settings["figure4b"]["points"],
        source=settings["figure4b"]["source"],
    )
