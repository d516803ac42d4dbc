"""Rule assemble_space: the curves of one simulated space -> its database."""

# BLAS/OpenMP pools sized to the job's threads, before NumPy is imported (the
# Snakemake preamble does not import it; skinsuction's __init__ is lazy).
from skinsuction._threads import limit_threads

limit_threads(snakemake.threads)

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
    from skinsuction.space import assemble_space

    assemble_space(
        snakemake.input.curves,
        snakemake.output.space,
        config=snakemake.config,
        name=snakemake.wildcards.space,
    )
