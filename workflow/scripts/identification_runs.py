"""Rule identification_runs: 100 identifications per case (Figures 4, 7, 8)."""

# BLAS/OpenMP pools sized to the job's threads, before NumPy is imported (the
# Snakemake preamble does not import it; skinsuction's __init__ is lazy).
from skinsuction._threads import limit_threads

limit_threads(snakemake.threads)

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
    from skinsuction.paper import write_runs

    write_runs(
        snakemake.wildcards.study,
        snakemake.input.space,
        snakemake.input.curves,
        snakemake.output.runs,
        settings=dict(snakemake.params.settings),
        alphas=list(snakemake.params.alphas),
    )
