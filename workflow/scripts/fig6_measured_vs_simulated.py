"""Rule fig6_measured_vs_simulated: Figure 6 and its table."""

from skinsuction.provenance import log_to_file

with log_to_file(snakemake.log[0]):
    from skinsuction.figures.fig6 import build_fig6

    build_fig6(
        snakemake.input.report,
        snakemake.input.check,
        png=snakemake.output.png,
        pdf=snakemake.output.pdf,
        csv=snakemake.output.table,
    )
