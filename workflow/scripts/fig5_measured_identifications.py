"""Rule fig5_measured_identifications: Figure 5 and its table."""

# BLAS/OpenMP pools sized to the job's threads, before NumPy is imported (the
# Snakemake preamble does not import it; skinsuction's __init__ is lazy).
from skinsuction._threads import limit_threads

limit_threads(snakemake.threads)

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
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
