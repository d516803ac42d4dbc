"""Rule timing_table: iterations and seconds per identification (CSV, Markdown)."""

from skinsuction.jobs import job

with job(snakemake.log[0], threads=snakemake.threads):
    from skinsuction.paper import build_timing

    build_timing(
        snakemake.input.space,
        snakemake.input.curves,
        csv=snakemake.output.table,
        markdown=snakemake.output.markdown,
        runs_csv=snakemake.output.runs,
        settings=dict(snakemake.params.settings),
    )
