"""Rule convergence_table: converged point counts of a simulated space."""

from skinsuction.provenance import log_to_file

with log_to_file(snakemake.log[0]):
    from skinsuction.space import read_space, write_table

    write_table(read_space(snakemake.input.space).convergence_summary(), snakemake.output.table)
