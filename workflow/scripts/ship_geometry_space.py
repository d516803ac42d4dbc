"""Rule ship_geometry_space (developer): copy the built geometry space into the package, with PROVENANCE.json."""

from skinsuction.jobs import job

with job(snakemake.log[0]):
    from skinsuction.space import ship_geometry_space

    record = ship_geometry_space(snakemake.input.space[0], snakemake.params.dest,
                                 build_command=snakemake.params.build_command,
                                 repo=snakemake.params.repo)
    print(f"{record['rays']} rays ({record['stopped_early']} stopped early), "
          f"{record['files']['neo_hookean.parquet']['bytes']} bytes")
