"""Rules detectability_map and confusion_given_layers: the draws' rows (of single draws or
shards) -> confusion matrix, rates, map."""

from skinsuction.jobs import job, write_table

with job(snakemake.log[0]):
    import pandas as pd

    from skinsuction.evaluation import summarise
    from skinsuction.figures.detectability import plot_detectability

    rows = pd.concat([pd.read_csv(f) for f in snakemake.input.rows], ignore_index=True)
    # shards hold every n-th draw: by seed, the order of one run (none, then each cause)
    rows = rows.sort_values("seed", kind="stable", ignore_index=True)
    for col in ("cpu_seconds", "wall_seconds", "verdict", "detectable"):
        if col not in rows:  # no draw got that far (e.g. every FE run failed)
            rows[col] = float("nan")
    write_table(rows, snakemake.output.draws)
    s = summarise(rows, list(snakemake.params.causes))
    write_table(s["detectable"].reset_index(), snakemake.output.matrix)
    write_table(s["rates"], snakemake.output.rates)
    plot_detectability(rows, snakemake.output.png, snakemake.output.pdf)
