"""Rule simulate_ray: one FE ray of the diagnosis spaces (one curve at X1d = X1d_min)."""

import os

# One job per core: keep BLAS/OpenMP pools to the rule's threads. Must be set
# before NumPy is imported (the Snakemake preamble does not import it).
for _var in (
    "OMP_NUM_THREADS",
    "OPENBLAS_NUM_THREADS",
    "MKL_NUM_THREADS",
    "NUMEXPR_NUM_THREADS",
    "VECLIB_MAXIMUM_THREADS",
):
    os.environ[_var] = str(snakemake.threads)

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
    from skinsuction.diagnose import compute_ray

    compute_ray(
        snakemake.wildcards.ray,
        snakemake.output.ray,
        pressures_mbar=snakemake.params.pressures,
        mesh=dict(snakemake.params.mesh),
        metadata={"source_hash": {"model": snakemake.params.code}},
    )
