"""Rule scale_free_coverage: the coverage frontier of the scale-free space, table and figure."""

from skinsuction.jobs import job, write_table

with job(snakemake.log[0], threads=snakemake.threads):
    import pandas as pd

    from skinsuction.space import coverage_frontier, read_ray_space
    from skinsuction.figures.coverage import plot_coverage

    frontier = pd.concat([coverage_frontier(read_ray_space(p)) for p in snakemake.input.spaces],
                         ignore_index=True)
    write_table(frontier, snakemake.output.table)
    plot_coverage(frontier, snakemake.output.png, snakemake.output.pdf)
