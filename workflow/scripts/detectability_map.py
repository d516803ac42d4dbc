"""Rule detectability_map: the diagnosis over the physiological domain (confusion, map)."""

# One process per thread, each with single-threaded BLAS/OpenMP pools: set before
# NumPy is imported (the Snakemake preamble does not import it; skinsuction's
# __init__ is lazy).
from skinsuction._threads import limit_threads

limit_threads(1)

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
    import sys

    from skinsuction.diagnose import Settings
    from skinsuction.space import read_ray_space
    from skinsuction.diagnose._confusion import run_draws, summarise
    from skinsuction.figures.detectability import plot_detectability
    from skinsuction._files import write_table

    spaces = {s.name: s for s in map(read_ray_space, snakemake.input.spaces)}
    settings = Settings.from_config(snakemake.params.decision, snakemake.params.fit)
    # the rule with the layers given: a domain with a given dermis, rays on demand
    domain = snakemake.params.get("domain")
    on_demand = None
    if snakemake.params.get("on_demand_dir"):
        from skinsuction.space import OnDemandRays

        spec = spaces["neo_hookean"].spec
        on_demand = OnDemandRays(spec, cache_dir=snakemake.params.on_demand_dir,
                                 progress=None)
    if domain:
        domain = {**domain, "probe_pairs": tuple(tuple(float(q) for q in pair)
                                                 for pair in domain.get("probe_pairs", ()))}
        given = domain.get("given_dermis_thickness")
        if given:
            domain["given_dermis_thickness"] = {"range": tuple(given["range"]),
                                                "sd": float(given["sd"])}
    rows = run_draws(spaces, snakemake.params.per_cause, snakemake.params.seed, settings,
                     workers=snakemake.threads, progress=sys.stderr, domain=domain,
                     on_demand=on_demand)
    write_table(rows, snakemake.output.draws)
    causes = [n for n in spaces if n != "neo_hookean"
              and not (domain and domain.get("given_dermis_thickness")
                       and spaces[n].cause.keyword == "t_d")]
    s = summarise(rows, causes)
    write_table(s["detectable"].reset_index(), snakemake.output.matrix)
    write_table(s["rates"], snakemake.output.rates)
    plot_detectability(rows, snakemake.output.png, snakemake.output.pdf)
