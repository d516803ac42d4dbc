"""Rule fig8_ratio: Figure 8 and its tables."""

from skinsuction.jobs import job

with job(snakemake.log[0], threads=snakemake.threads):
    from skinsuction.paper import build_fig8

    build_fig8(
        snakemake.input.space,
        snakemake.input.curves,
        snakemake.input.runs,
        png=snakemake.output.png,
        pdf=snakemake.output.pdf,
        csv=snakemake.output.table,
        curves_csv=snakemake.output.ratio_curves,
        settings=dict(snakemake.params.settings),
    )
