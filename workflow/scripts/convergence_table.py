"""Rule convergence_table: converged point counts of a simulated space."""

# BLAS/OpenMP pools sized to the job's threads, before NumPy is imported (the
# Snakemake preamble does not import it; skinsuction's __init__ is lazy).
from skinsuction._threads import limit_threads

limit_threads(snakemake.threads)

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
    from skinsuction.space import read_space
    from skinsuction._files import write_table

    write_table(read_space(snakemake.input.space).convergence_summary(), snakemake.output.table)
