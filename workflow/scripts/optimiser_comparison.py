"""Rule optimiser_comparison: window focusing vs scipy optimisers (CSV, Markdown)."""

from skinsuction.jobs import job

with job(snakemake.log[0], threads=snakemake.threads):
    from skinsuction.paper import build_comparison

    build_comparison(
        snakemake.input.space,
        snakemake.input.curves,
        snakemake.input.fe_loop,
        csv=snakemake.output.table,
        markdown=snakemake.output.markdown,
        runs_csv=snakemake.output.runs,
        settings=dict(snakemake.params.settings),
    )
