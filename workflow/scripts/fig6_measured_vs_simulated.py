"""Rule fig6_measured_vs_simulated: Figure 6 and its table."""

from skinsuction.jobs import job

with job(snakemake.log[0], threads=snakemake.threads):
    from skinsuction.paper import build_fig6

    build_fig6(
        snakemake.input.report,
        snakemake.input.check,
        png=snakemake.output.png,
        pdf=snakemake.output.pdf,
        csv=snakemake.output.table,
    )
