"""Rule assemble_geometry_space: a model's rays of every t_d/a node -> its geometry space."""

from skinsuction.jobs import job

with job(snakemake.log[0], threads=snakemake.threads):
    from skinsuction.provenance import collect
    from skinsuction.space import GeometryGrid, RaySpec, assemble_geometry_space, \
        registry_from_config

    name = snakemake.params.cause
    cause = None if name is None else registry_from_config(snakemake.params.causes)[name]
    space = assemble_geometry_space(
        snakemake.input.bundles, snakemake.output.space, RaySpec(**snakemake.params.spec),
        GeometryGrid.from_config(snakemake.params.grid), provenance=collect(snakemake.config),
        cause=cause)
    print(f"{name or 'neo_hookean'}: {space.deflection.shape[0] * space.deflection.shape[1]} "
          f"geometries x {len(space.coordinates)} nodes x {len(space.spec.ratio_nodes)} "
          f"X1h/X1d -> {snakemake.output.space}")
