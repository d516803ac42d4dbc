"""Rule diagnose_measured: `skinsuction diagnose` of one measured file of the config."""

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ[_var] = "1"

import logging  # noqa: E402
from pathlib import Path  # noqa: E402

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
    from skinsuction.diagnose import Settings, diagnose_file, read_ray_space, write_report

    spaces = {s.name: s for s in map(read_ray_space, snakemake.input.spaces)}
    settings = Settings.from_config(snakemake.params.decision, snakemake.params.fit)
    report = diagnose_file(snakemake.input.measured, Path(snakemake.input.spaces[0]).parent,
                           settings, spaces=spaces)
    write_report(report, Path(snakemake.output.json).parent)
    logging.getLogger("skinsuction.diagnose").info("%s", report["summary"])
