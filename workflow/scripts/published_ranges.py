"""Rule published_ranges: creep alone, or creep with stiffening, against the published
Cutometer values of the face (FE mode-1 curves; table, summary, figure)."""

from skinsuction.jobs import job, write_table

# one process per thread, each with single-threaded BLAS/OpenMP pools
with job(snakemake.log[0], threads=1):
    from skinsuction.evaluation import (
        PUBLISHED_FACE,
        published_ranges_markdown,
        published_ranges_study,
    )
    from skinsuction.figures.published import plot_published_ranges
    from skinsuction.results import write_text

    s = dict(snakemake.params.settings)
    mesh = {**snakemake.params.mesh, **s.pop("mesh", {})}
    frame = published_ranges_study(processes=snakemake.threads, mesh=mesh, **s)
    write_table(frame, snakemake.output.draws)
    write_text(snakemake.output.summary, published_ranges_markdown(frame, s, mesh))
    plot_published_ranges(frame, PUBLISHED_FACE, snakemake.output.png, snakemake.output.pdf)
