"""Rule diagnose_time_curves: `skinsuction diagnose` of one time-curve file of the config."""

import logging
from pathlib import Path

from skinsuction.jobs import job

with job(snakemake.log[0], threads=snakemake.threads):
    from skinsuction.diagnose import Settings, diagnose_time_file, write_time_report

    settings = Settings.from_config(snakemake.params.decision, snakemake.params.fit)
    report = diagnose_time_file(snakemake.input.measured,
                                Path(snakemake.input.spaces[0]).parent, settings)
    write_time_report(report, Path(snakemake.output.json).parent)
    logging.getLogger("skinsuction.diagnose").info("%s", report["summary"])
