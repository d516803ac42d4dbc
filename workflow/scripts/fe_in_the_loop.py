"""Rule fe_in_the_loop: least squares with the FE model in the loop, once."""

# BLAS/OpenMP pools sized to the job's threads, before NumPy is imported (the
# Snakemake preamble does not import it; skinsuction's __init__ is lazy).
from skinsuction._threads import limit_threads

limit_threads(snakemake.threads)

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
    from skinsuction.paper import write_fe_in_the_loop

    write_fe_in_the_loop(
        snakemake.input.space,
        snakemake.output.result,
        settings=dict(snakemake.params.settings),
        loop=dict(snakemake.params.loop),
        pressures_mbar=list(snakemake.params.pressures),
    )
