"""Rule fig5_measured_identifications: Figure 5 and its table."""

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ[_var] = "1"

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
    from skinsuction.figures.fig5 import build_fig5

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
