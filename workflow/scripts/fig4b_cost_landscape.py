"""Rule fig4b_cost_landscape: Figure 4b (cost landscapes), its table and data."""

# BLAS/OpenMP pools sized to the job's threads, before NumPy is imported (the
# Snakemake preamble does not import it; skinsuction's __init__ is lazy).
from skinsuction._threads import limit_threads

limit_threads(snakemake.threads)

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
    from skinsuction.paper import build_fig4b

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
