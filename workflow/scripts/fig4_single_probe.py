"""Rule fig4_single_probe: Figure 4 and its table."""

from skinsuction.jobs import job

with job(snakemake.log[0], threads=snakemake.threads):
    from skinsuction.paper import build_fig4

    t = snakemake.params.target
    build_fig4(
        snakemake.input.runs,
        png=snakemake.output.png,
        pdf=snakemake.output.pdf,
        csv=snakemake.output.table,
        target=(t["x1d"], t["x1h"]),
        success_tolerance=snakemake.params.success_tolerance,
    )
