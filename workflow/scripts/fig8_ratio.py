"""Rule fig8_ratio: Figure 8 and its tables."""

# BLAS/OpenMP pools sized to the job's threads, before NumPy is imported (the
# Snakemake preamble does not import it; skinsuction's __init__ is lazy).
from skinsuction._threads import limit_threads

limit_threads(snakemake.threads)

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
    from skinsuction.paper import build_fig8

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
