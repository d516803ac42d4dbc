"""Rule fig4b_cost_landscape: Figure 4b (cost landscapes), its table and data."""

from skinsuction.jobs import job

with job(snakemake.log[0], threads=snakemake.threads):
    from skinsuction.paper import build_fig4b

    settings = dict(snakemake.params.settings)
    build_fig4b(
        snakemake.input.space,
        snakemake.input.curves,
        png=snakemake.output.png,
        pdf=snakemake.output.pdf,
        csv=snakemake.output.table,
        landscape_out=snakemake.output.landscape,
        settings=settings,
        points=settings["figure4b"]["points"],
        source=settings["figure4b"]["source"],
    )
