"""Rule identification_runs: 100 identifications per case (Figures 4, 7, 8)."""

import os

# One BLAS/OpenMP thread (before NumPy is imported): jobs run side by side, and the
# timings are single-thread timings.
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ[_var] = "1"

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
    from skinsuction.identify.study import write_runs

    write_runs(
        snakemake.wildcards.study,
        snakemake.input.space,
        snakemake.input.curves,
        snakemake.output.runs,
        settings=dict(snakemake.params.settings),
        alphas=list(snakemake.params.alphas),
    )
