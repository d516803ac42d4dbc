"""Rule confusion_given_layers_draw: one virtual experiment, diagnosed (one row)."""

from skinsuction.jobs import job, write_table

with job(snakemake.log[0], threads=1):
    import pandas as pd

    from skinsuction.diagnose import Settings
    from skinsuction.evaluation import domain_from_config, run_draw
    from skinsuction.space import OnDemandRays, read_ray_space

    spaces = {s.name: s for s in map(read_ray_space, snakemake.input.spaces)}
    settings = Settings.from_config(snakemake.params.decision, snakemake.params.fit)
    domain = domain_from_config(snakemake.params.domain)
    truth, seed = snakemake.wildcards.draw.rsplit("_", 1)
    on_demand = OnDemandRays(spaces["neo_hookean"].spec,
                             cache_dir=snakemake.params.on_demand_dir)
    row = run_draw(truth, int(seed), spaces, settings, domain, on_demand=on_demand)
    write_table(pd.DataFrame([row]), snakemake.output.row)
