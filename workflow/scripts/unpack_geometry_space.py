"""Rule unpack_geometry_space (developer): a shipped geometry space back in job files."""

from skinsuction.jobs import job

with job(snakemake.log[0], threads=snakemake.threads):
    import collections
    import json

    from skinsuction.jobs import atomic_output
    from skinsuction.space import registry_from_config, unpack_geometry_space

    name = snakemake.params.cause
    cause = None if name is None else registry_from_config(snakemake.params.causes)[name]
    done = unpack_geometry_space(snakemake.input.space, snakemake.params.jobs,
                                 snakemake.params.out_dir, cause=cause,
                                 source_hash=snakemake.params.code)
    counts = collections.Counter(done.values())
    print(f"{name or 'neo_hookean'}: {dict(counts)} of {len(done)} jobs")
    with atomic_output(snakemake.output.manifest) as tmp:
        tmp.write_text(json.dumps({"space": snakemake.input.space, "jobs": done}, indent=1))
