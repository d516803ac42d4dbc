"""Rule ramp_effects_confusion: single and paired effects in pressure ramps, named with
the pair spaces (FE draws; table, summary, figure)."""

from skinsuction.jobs import job, write_table

# one process per thread, each with single-threaded BLAS/OpenMP pools
with job(snakemake.log[0], threads=1):
    from skinsuction.evaluation import (
        ramp_effects_markdown,
        ramp_effects_study,
        ramp_effects_summary,
    )
    from skinsuction.figures.effects import plot_effects_confusion
    from skinsuction.results import write_text

    s = dict(snakemake.params.settings)
    frame = ramp_effects_study(s["per_class"], s.get("seed", 0), s.get("designs"),
                               processes=snakemake.threads)
    write_table(frame, snakemake.output.draws)
    write_text(snakemake.output.summary, ramp_effects_markdown(frame))
    plot_effects_confusion(ramp_effects_summary(frame), snakemake.output.png,
                           snakemake.output.pdf)
