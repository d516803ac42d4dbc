"""Rules ship_geometry_space and ship_geometry_model (developer): copy built geometry
spaces into the package, with PROVENANCE.json."""

from skinsuction.jobs import job

with job(snakemake.log[0]):
    import json
    from pathlib import Path

    from skinsuction.jobs import atomic_output
    from skinsuction.space import ship_geometry_space

    shipped, spaces = {}, snakemake.input.space
    for built in [spaces] if isinstance(spaces, str) else spaces:
        record = ship_geometry_space(built, snakemake.params.dest,
                                     build_command=snakemake.params.build_command,
                                     repo=snakemake.params.repo)
        one = shipped[Path(built).name] = record["files"][Path(built).name]
        print(f"{Path(built).name}: {one['rays']} rays ({one['stopped_early']} stopped early), "
              f"{one['bytes']} bytes")
    if snakemake.output:
        with atomic_output(snakemake.output[0]) as tmp:
            tmp.write_text(json.dumps(shipped, indent=1))
