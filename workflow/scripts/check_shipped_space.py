"""Rule check_shipped_space: the fresh scale-free space against the one shipped with skinsuction."""

from pathlib import Path

from skinsuction.jobs import job

with job(snakemake.log[0], threads=snakemake.threads):
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
