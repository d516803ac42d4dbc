"""Rule scale_free_vs_paper: the honest test curve on the paper grid and the scale-free space."""

# BLAS/OpenMP pools sized to the job's threads, before NumPy is imported (the
# Snakemake preamble does not import it; skinsuction's __init__ is lazy).
from skinsuction._threads import limit_threads

limit_threads(snakemake.threads)

from pathlib import Path  # noqa: E402

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
    from skinsuction.paper import write_space_comparison

    write_space_comparison(
        snakemake.input.paper,
        Path(snakemake.input.scale_free).parent,
        snakemake.input.curves,
        snakemake.output.table,
        snakemake.output.md,
        snakemake.output.runs,
        settings=dict(snakemake.params.settings),
    )
