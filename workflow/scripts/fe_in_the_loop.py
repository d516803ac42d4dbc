"""Rule fe_in_the_loop: least squares with the FE model in the loop, once."""

import os

# One BLAS/OpenMP thread (before NumPy is imported): jobs run side by side, and the
# timings are single-thread timings.
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ[_var] = "1"

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
    from skinsuction.identify.study import write_fe_in_the_loop

    write_fe_in_the_loop(
        snakemake.input.space,
        snakemake.output.result,
        settings=dict(snakemake.params.settings),
        loop=dict(snakemake.params.loop),
        pressures_mbar=list(snakemake.params.pressures),
    )
