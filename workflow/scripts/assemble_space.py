"""Rule assemble_space: the curves of one simulated space -> its database."""

from skinsuction.provenance import log_to_file

with log_to_file(snakemake.log[0]):
    from skinsuction.space import assemble_space

    assemble_space(
        snakemake.input.curves,
        snakemake.output.space,
        config=snakemake.config,
        name=snakemake.wildcards.space,
    )
