"""Rule fig7_alpha: Figure 7, its table and the alpha threshold."""

from skinsuction.jobs import job

with job(snakemake.log[0], threads=snakemake.threads):
    from skinsuction.paper import build_fig7

    t = snakemake.params.target
    build_fig7(
        snakemake.input.runs,
        png=snakemake.output.png,
        pdf=snakemake.output.pdf,
        csv=snakemake.output.table,
        threshold_csv=snakemake.output.threshold,
        target=(t["x1d"], t["x1h"]),
        success_tolerance=snakemake.params.success_tolerance,
    )
