"""Rule fig4_single_probe: Figure 4 and its table."""

# BLAS/OpenMP pools sized to the job's threads, before NumPy is imported (the
# Snakemake preamble does not import it; skinsuction's __init__ is lazy).
from skinsuction._threads import limit_threads

limit_threads(snakemake.threads)

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
    from skinsuction.paper import build_fig4

    t = snakemake.params.target
    build_fig4(
        snakemake.input.runs,
        png=snakemake.output.png,
        pdf=snakemake.output.pdf,
        csv=snakemake.output.table,
        target=(t["x1d"], t["x1h"]),
        success_tolerance=snakemake.params.success_tolerance,
    )
