"""Rule assemble_pair_space: a pair's ray bundles and its two causes' spaces -> its space."""

from skinsuction.jobs import job

with job(snakemake.log[0], threads=snakemake.threads):
    from skinsuction.space import CausePair, RaySpec, assemble_pair_space, read_ray_space

    singles = {s.name: s for s in map(read_ray_space, snakemake.input.singles)}
    assemble_pair_space(snakemake.input.bundles, singles, snakemake.output.space,
                        RaySpec(**snakemake.params.spec), CausePair.from_dict(snakemake.params.pair),
                        config=snakemake.config)
