"""Rule ship_geometry_space (developer): copy the built geometry spaces into the package, with PROVENANCE.json."""

from skinsuction.jobs import job

with job(snakemake.log[0]):
    from skinsuction.space import ship_geometry_space

    from pathlib import Path

    for built in snakemake.input.space:
        record = ship_geometry_space(built, snakemake.params.dest,
                                     build_command=snakemake.params.build_command,
                                     repo=snakemake.params.repo)
        one = record["files"][Path(built).name]
        print(f"{Path(built).name}: {one['rays']} rays ({one['stopped_early']} stopped early), "
              f"{one['bytes']} bytes")
