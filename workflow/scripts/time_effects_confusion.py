"""Rule time_effects_confusion: single and paired effects in Cutometer time curves,
named effect by effect (FE draws; table, summary, figure)."""

from skinsuction.jobs import job, write_table

# one process per thread, each with single-threaded BLAS/OpenMP pools
with job(snakemake.log[0], threads=1):
    from skinsuction.evaluation import (
        effects_confusion_markdown,
        effects_confusion_study,
        effects_confusion_summary,
    )
    from skinsuction.figures.effects import plot_effects_confusion
    from skinsuction.results import write_text

    s = dict(snakemake.params.settings)
    frame = effects_confusion_study(s["per_class"], s.get("seed", 0), s.get("designs"),
                                    processes=snakemake.threads)
    write_table(frame, snakemake.output.draws)
    write_text(snakemake.output.summary, effects_confusion_markdown(frame))
    plot_effects_confusion(effects_confusion_summary(frame), snakemake.output.png,
                           snakemake.output.pdf)
