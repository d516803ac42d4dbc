"""Rule scale_free_coverage: the coverage frontier of the scale-free space, table and figure."""

from skinsuction.provenance import log_to_file

with log_to_file(snakemake.log[0]):
    import pandas as pd

    from skinsuction.diagnose import coverage_frontier, read_ray_space
    from skinsuction.figures.coverage import plot_coverage
    from skinsuction.space import write_table

    frontier = pd.concat([coverage_frontier(read_ray_space(p)) for p in snakemake.input.spaces],
                         ignore_index=True)
    write_table(frontier, snakemake.output.table)
    plot_coverage(frontier, snakemake.output.png, snakemake.output.pdf)
