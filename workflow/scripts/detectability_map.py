"""Rule detectability_map: the diagnosis over the physiological domain (confusion, map)."""

from skinsuction.jobs import job, write_table

# one process per thread, each with single-threaded BLAS/OpenMP pools
with job(snakemake.log[0], threads=1):
    import sys

    from skinsuction.diagnose import Settings
    from skinsuction.space import read_ray_space
    from skinsuction.evaluation import run_draws, summarise
    from skinsuction.figures.detectability import plot_detectability

    spaces = {s.name: s for s in map(read_ray_space, snakemake.input.spaces)}
    settings = Settings.from_config(snakemake.params.decision, snakemake.params.fit)
    rows = run_draws(spaces, snakemake.params.per_cause, snakemake.params.seed, settings,
                     workers=snakemake.threads, progress=sys.stderr)
    write_table(rows, snakemake.output.draws)
    s = summarise(rows, [n for n in spaces if n != "neo_hookean"])
    write_table(s["detectable"].reset_index(), snakemake.output.matrix)
    write_table(s["rates"], snakemake.output.rates)
    plot_detectability(rows, snakemake.output.png, snakemake.output.pdf)
