"""Rule check_shipped_space: the fresh scale-free space against the one shipped with skinsuction."""

# BLAS/OpenMP pools sized to the job's threads, before NumPy is imported (the
# Snakemake preamble does not import it; skinsuction's __init__ is lazy).
from skinsuction._threads import limit_threads

limit_threads(snakemake.threads)

from pathlib import Path  # noqa: E402

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
    from skinsuction.space import RaySpec, check_shipped_space, registry_from_config

    check_shipped_space(
        Path(snakemake.input.spaces[0]).parent,
        snakemake.output.table,
        RaySpec(**snakemake.params.spec),
        registry_from_config(dict(snakemake.params.causes)),
        shipped_dir=snakemake.params.shipped_dir,
        rtol=snakemake.params.rtol,
        atol=snakemake.params.atol,
    )
