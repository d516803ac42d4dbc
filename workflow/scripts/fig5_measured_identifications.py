"""Rule fig5_measured_identifications: Figure 5 and its table."""

from skinsuction.jobs import job

with job(snakemake.log[0], threads=snakemake.threads):
    from skinsuction.paper import build_fig5

    s = snakemake.params.settings
    build_fig5(
        snakemake.input.measured,
        snakemake.input.space,
        png=snakemake.output.png,
        pdf=snakemake.output.pdf,
        csv=snakemake.output.table,
        runs_csv=snakemake.output.runs,
        probe_mm=s["probe_mm"],
        repeats=s["repeats"],
        seed=s["seed"],
        window_focusing=s.get("window_focusing"),
    )
