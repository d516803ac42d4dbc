"""Rule fe_in_the_loop: least squares with the FE model in the loop, once."""

from skinsuction.jobs import job

with job(snakemake.log[0], threads=snakemake.threads):
    from skinsuction.paper import write_fe_in_the_loop

    write_fe_in_the_loop(
        snakemake.input.space,
        snakemake.output.result,
        settings=dict(snakemake.params.settings),
        loop=dict(snakemake.params.loop),
        pressures_mbar=list(snakemake.params.pressures),
    )
