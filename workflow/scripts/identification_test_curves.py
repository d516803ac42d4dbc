"""Rule identification_test_curves: FE and interpolated curves at the test point."""

# BLAS/OpenMP pools sized to the job's threads, before NumPy is imported (the
# Snakemake preamble does not import it; skinsuction's __init__ is lazy).
from skinsuction._threads import limit_threads

limit_threads(snakemake.threads)

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
    from skinsuction.paper import make_test_curves

    t = snakemake.params.target
    make_test_curves(
        snakemake.input.space,
        snakemake.input.fe,
        snakemake.output.curves,
        target=(t["x1d"], t["x1h"]),
        bottom=snakemake.params.bottom,
    )
