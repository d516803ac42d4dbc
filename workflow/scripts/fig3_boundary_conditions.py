"""Rule fig3_boundary_conditions: Figure 3 of the paper and its table."""

from skinsuction.jobs import job

with job(snakemake.log[0], threads=snakemake.threads):
    from skinsuction.figures.fig3 import build_fig3

    build_fig3(
        snakemake.input.curves,
        png=snakemake.output.png,
        pdf=snakemake.output.pdf,
        csv=snakemake.output.table,
        pressure_mbar=snakemake.params.pressure_mbar,
        points=snakemake.params.points,
    )
