"""Rule diagnose_time_curves: `skinsuction diagnose` of one time-curve file of the config."""

# BLAS/OpenMP pools sized to the job's threads, before NumPy is imported (the
# Snakemake preamble does not import it; skinsuction's __init__ is lazy).
from skinsuction._threads import limit_threads

limit_threads(snakemake.threads)

import logging  # noqa: E402
from pathlib import Path  # noqa: E402

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
    from skinsuction.diagnose import Settings
    from skinsuction.diagnose._time import diagnose_time_file, write_time_report

    settings = Settings.from_config(snakemake.params.decision, snakemake.params.fit)
    report = diagnose_time_file(snakemake.input.measured,
                                Path(snakemake.input.spaces[0]).parent, settings)
    write_time_report(report, Path(snakemake.output.json).parent)
    logging.getLogger("skinsuction.diagnose").info("%s", report["summary"])
