"""Rule scale_free_coverage: the coverage frontier of the scale-free space, table and figure."""

# BLAS/OpenMP pools sized to the job's threads, before NumPy is imported (the
# Snakemake preamble does not import it; skinsuction's __init__ is lazy).
from skinsuction._threads import limit_threads

limit_threads(snakemake.threads)

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
    import pandas as pd

    from skinsuction.space import coverage_frontier, read_ray_space
    from skinsuction.figures.coverage import plot_coverage
    from skinsuction._files import write_table

    frontier = pd.concat([coverage_frontier(read_ray_space(p)) for p in snakemake.input.spaces],
                         ignore_index=True)
    write_table(frontier, snakemake.output.table)
    plot_coverage(frontier, snakemake.output.png, snakemake.output.pdf)
