"""Rule assemble_geometry_space: the rays of every t_d/a node -> the geometry space."""

from skinsuction.jobs import job

with job(snakemake.log[0], threads=snakemake.threads):
    from skinsuction.provenance import collect
    from skinsuction.space import GeometryGrid, RaySpec, assemble_geometry_space

    space = assemble_geometry_space(
        snakemake.input.bundles, snakemake.output.space, RaySpec(**snakemake.params.spec),
        GeometryGrid.from_config(snakemake.params.grid), provenance=collect(snakemake.config))
    print(f"{space.deflection.shape[0] * space.deflection.shape[1]} geometries x "
          f"{space.deflection.shape[2]} X1h/X1d nodes -> {snakemake.output.space}")
