"""Rule timing_table: iterations and seconds per identification (CSV, Markdown)."""

import os

# One BLAS/OpenMP thread (before NumPy is imported): jobs run side by side, and the
# timings are single-thread timings.
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ[_var] = "1"

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
    from skinsuction.figures.tables import build_timing

    build_timing(
        snakemake.input.space,
        snakemake.input.curves,
        csv=snakemake.output.table,
        markdown=snakemake.output.markdown,
        runs_csv=snakemake.output.runs,
        settings=dict(snakemake.params.settings),
    )
