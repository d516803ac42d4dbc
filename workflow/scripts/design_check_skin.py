"""Rule design_check_skin: one skin, one design, predicted and measured (one row)."""

from skinsuction.jobs import job, write_table

with job(snakemake.log[0], threads=1):
    import pandas as pd

    from skinsuction.design import Box, check_skin, parse_design
    from skinsuction.diagnose import Settings
    from skinsuction.space import OnDemandRays, pairs_for, read_ray_space

    s = snakemake.params.settings
    given = dict(s.get("given") or {})
    design = parse_design(snakemake.wildcards.design, noise_um=snakemake.params.noise_um,
                          resolution_mm=snakemake.params.resolution_mm, given=given)
    i = int(snakemake.wildcards.skin)
    seed = s.get("seed", 1)
    skins = Box.from_config(snakemake.params.box).draw(s.get("skins", 60), seed)
    spaces = {sp.name: sp for sp in map(read_ray_space, snakemake.input.spaces)}
    on_demand = (OnDemandRays(spaces["neo_hookean"].spec,
                              cache_dir=snakemake.params.on_demand_dir) if given else False)
    # the seed of the benchmark's job (benchmarks/design_check.py): the same rows
    j = list(s["designs"]).index(snakemake.wildcards.design)
    row = check_skin(skins.iloc[i].to_dict(), design, seed + 100 * i + j, spaces,
                     Settings(seed=seed + 100 * i + j),
                     causes=tuple(s.get("causes", ())),
                     pairs=pairs_for(None, spaces["neo_hookean"].spec), on_demand=on_demand)
    write_table(pd.DataFrame([row]), snakemake.output.row)
