"""Rule optimiser_comparison: window focusing vs scipy optimisers (CSV, Markdown)."""

# BLAS/OpenMP pools sized to the job's threads, before NumPy is imported (the
# Snakemake preamble does not import it; skinsuction's __init__ is lazy).
from skinsuction._threads import limit_threads

limit_threads(snakemake.threads)

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
    from skinsuction.paper import build_comparison

    build_comparison(
        snakemake.input.space,
        snakemake.input.curves,
        snakemake.input.fe_loop,
        csv=snakemake.output.table,
        markdown=snakemake.output.markdown,
        runs_csv=snakemake.output.runs,
        settings=dict(snakemake.params.settings),
    )
