"""Rule assemble_space: the curves of one simulated space -> its database."""

from skinsuction.jobs import job

with job(snakemake.log[0], threads=snakemake.threads):
    from skinsuction.space import assemble_space

    assemble_space(
        snakemake.input.curves,
        snakemake.output.space,
        config=snakemake.config,
        name=snakemake.wildcards.space,
        points=snakemake.params.points,
    )
