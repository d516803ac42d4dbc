"""Rule convergence_table: converged point counts of a simulated space."""

from skinsuction.jobs import job, write_table

with job(snakemake.log[0], threads=snakemake.threads):
    from skinsuction.space import read_space

    write_table(read_space(snakemake.input.space).convergence_summary(), snakemake.output.table)
