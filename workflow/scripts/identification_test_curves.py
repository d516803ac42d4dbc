"""Rule identification_test_curves: FE and interpolated curves at the test point."""

import os

# One BLAS/OpenMP thread (before NumPy is imported): jobs run side by side, and the
# timings are single-thread timings.
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ[_var] = "1"

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
    from skinsuction.identify.study import make_test_curves

    t = snakemake.params.target
    make_test_curves(
        snakemake.input.space,
        snakemake.input.fe,
        snakemake.output.curves,
        target=(t["x1d"], t["x1h"]),
        bottom=snakemake.params.bottom,
    )
