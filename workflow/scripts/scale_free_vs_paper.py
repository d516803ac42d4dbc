"""Rule scale_free_vs_paper: the honest test curve on the paper grid and the scale-free space."""

from pathlib import Path

from skinsuction._threads import limit_threads

limit_threads(1)  # single-thread timings, jobs side by side

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
    from skinsuction.identify.study import write_space_comparison

    write_space_comparison(
        snakemake.input.paper,
        Path(snakemake.input.scale_free).parent,
        snakemake.input.curves,
        snakemake.output.table,
        snakemake.output.md,
        snakemake.output.runs,
        settings=dict(snakemake.params.settings),
    )
