"""Rule assemble_scale_free_space: the ray bundles of one model -> its scale-free space."""

from skinsuction.jobs import job

with job(snakemake.log[0], threads=snakemake.threads):
    from skinsuction.diagnose import registry_from_config
    from skinsuction.space import RaySpec, assemble_ray_space

    spec = RaySpec(**snakemake.params.spec)
    name = snakemake.wildcards.model
    cause = None
    if snakemake.params.cause is not None:
        cause = registry_from_config({name: snakemake.params.cause})[name]
    assemble_ray_space(snakemake.input.bundles, snakemake.output.space, spec, cause,
                       config=snakemake.config)
