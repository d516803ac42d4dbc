"""Rule scale_free_vs_paper: the honest test curve on the paper grid and the scale-free space."""

from pathlib import Path

from skinsuction.jobs import job

with job(snakemake.log[0], threads=snakemake.threads):
    from skinsuction.paper import write_space_comparison

    write_space_comparison(
        snakemake.input.paper,
        Path(snakemake.input.scale_free).parent,
        snakemake.input.curves,
        snakemake.output.table,
        snakemake.output.md,
        snakemake.output.runs,
        settings=dict(snakemake.params.settings),
    )
