"""Rule fig7_alpha: Figure 7, its table and the alpha threshold."""

# BLAS/OpenMP pools sized to the job's threads, before NumPy is imported (the
# Snakemake preamble does not import it; skinsuction's __init__ is lazy).
from skinsuction._threads import limit_threads

limit_threads(snakemake.threads)

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
    from skinsuction.paper import build_fig7

    t = snakemake.params.target
    build_fig7(
        snakemake.input.runs,
        png=snakemake.output.png,
        pdf=snakemake.output.pdf,
        csv=snakemake.output.table,
        threshold_csv=snakemake.output.threshold,
        target=(t["x1d"], t["x1h"]),
        success_tolerance=snakemake.params.success_tolerance,
    )
