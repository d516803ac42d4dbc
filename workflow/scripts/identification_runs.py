"""Rule identification_runs: 100 identifications per case (Figures 4, 7, 8)."""

from skinsuction.jobs import job

with job(snakemake.log[0], threads=snakemake.threads):
    from skinsuction.paper import write_runs

    write_runs(
        snakemake.wildcards.study,
        snakemake.input.space,
        snakemake.input.curves,
        snakemake.output.runs,
        settings=dict(snakemake.params.settings),
        alphas=list(snakemake.params.alphas),
    )
