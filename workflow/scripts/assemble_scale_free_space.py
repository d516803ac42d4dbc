"""Rule assemble_scale_free_space: the ray bundles of one model -> its scale-free space."""

from skinsuction.provenance import log_to_file

with log_to_file(snakemake.log[0]):
    from skinsuction.diagnose import RaySpec, assemble_ray_space, registry_from_config

    spec = RaySpec(**snakemake.params.spec)
    name = snakemake.wildcards.model
    cause = None
    if snakemake.params.cause is not None:
        cause = registry_from_config({name: snakemake.params.cause})[name]
    assemble_ray_space(snakemake.input.bundles, snakemake.output.space, spec, cause,
                       config=snakemake.config)
