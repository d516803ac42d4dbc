"""Rule diagnose_measured: `skinsuction diagnose` of one measured file of the config."""

import logging
from pathlib import Path

from skinsuction.jobs import job

# one BLAS/OpenMP thread: the job's threads are the processes that solve rays on demand
with job(snakemake.log[0], threads=1):
    from skinsuction.diagnose import Settings, diagnose_file, write_report
    from skinsuction.space import BASELINE, OnDemandRays, read_ray_space

    spaces = {s.name: s for s in map(read_ray_space, snakemake.input.spaces)}
    settings = Settings.from_config(snakemake.params.decision, snakemake.params.fit)
    # a probe or layers the space lacks: its rays solved once, kept with the results
    solver = OnDemandRays(spaces[BASELINE].spec, cache_dir=snakemake.params.on_demand_dir,
                          workers=snakemake.threads)
    report = diagnose_file(snakemake.input.measured, Path(snakemake.input.spaces[0]).parent,
                           settings, spaces=spaces, on_demand=solver)
    write_report(report, Path(snakemake.output.json).parent)
    logging.getLogger("skinsuction.diagnose").info("%s", report["summary"])
