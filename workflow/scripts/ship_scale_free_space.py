"""Rule ship_scale_free_space (developer): copy the built space into the package, with PROVENANCE.json."""

from pathlib import Path

from skinsuction.jobs import job

with job(snakemake.log[0]):
    from skinsuction.space import ship_space

    record = ship_space(
        Path(snakemake.input.spaces[0]).parent,
        snakemake.params.dest,
        config_file=snakemake.params.config_file,
        build_command=snakemake.params.build_command,
        ship_command=snakemake.params.ship_command,
        repo=snakemake.params.repo,
    )
    for name, rec in record["files"].items():
        print(f"{name}: {rec['rows']} rows, {rec['rays']} rays, {rec['bytes']} bytes, "
              f"sha256 {rec['sha256'][:12]}")
