"""Rule assemble_scale_free_space: the ray bundles of one model -> its scale-free space."""

# BLAS/OpenMP pools sized to the job's threads, before NumPy is imported (the
# Snakemake preamble does not import it; skinsuction's __init__ is lazy).
from skinsuction._threads import limit_threads

limit_threads(snakemake.threads)

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
    from skinsuction.diagnose import registry_from_config
    from skinsuction.space import RaySpec, assemble_ray_space

    spec = RaySpec(**snakemake.params.spec)
    name = snakemake.wildcards.model
    cause = None
    if snakemake.params.cause is not None:
        cause = registry_from_config({name: snakemake.params.cause})[name]
    assemble_ray_space(snakemake.input.bundles, snakemake.output.space, spec, cause,
                       config=snakemake.config)
