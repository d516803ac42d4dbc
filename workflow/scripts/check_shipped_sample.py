"""Rule check_shipped_sample: the shipped space against a sample of its rays solved afresh."""

from skinsuction.jobs import job

with job(snakemake.log[0], threads=snakemake.threads):
    from skinsuction.space import RaySpec, check_shipped_sample, registry_from_config

    check_shipped_sample(
        snakemake.input.bundles,
        snakemake.output.table,
        RaySpec(**snakemake.params.spec),
        registry_from_config(dict(snakemake.params.causes)),
        shipped_dir=snakemake.params.shipped_dir,
        rtol=snakemake.params.rtol,
        atol=snakemake.params.atol,
    )
