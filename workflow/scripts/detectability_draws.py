"""Rule detectability_draws: one shard of the draws over the physiological domain."""

from skinsuction.jobs import job, write_table

with job(snakemake.log[0], threads=1):
    import sys

    from skinsuction.diagnose import Settings
    from skinsuction.evaluation import run_draws
    from skinsuction.space import read_ray_space

    spaces = {s.name: s for s in map(read_ray_space, snakemake.input.spaces)}
    settings = Settings.from_config(snakemake.params.decision, snakemake.params.fit)
    rows = run_draws(spaces, snakemake.params.per_cause, snakemake.params.seed, settings,
                     progress=sys.stderr,
                     shard=(int(snakemake.wildcards.shard), snakemake.params.shards))
    write_table(rows, snakemake.output.rows)
