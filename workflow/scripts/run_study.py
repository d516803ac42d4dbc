"""Rule study: `skinsuction study` of one study of the config."""

# BLAS/OpenMP pools sized to the job's threads, before NumPy is imported (the
# Snakemake preamble does not import it; skinsuction's __init__ is lazy).
from skinsuction._threads import limit_threads

limit_threads(snakemake.threads)

import logging  # noqa: E402
from pathlib import Path  # noqa: E402

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
    import sys

    from skinsuction.cohort import run_study

    s = snakemake.params.settings
    result = run_study(
        s["path"], Path(snakemake.output.curves).parent, space_dir=snakemake.params.space_dir,
        diagnose=s.get("diagnose", True), repeats=s.get("repeats", 2), seed=s.get("seed", 0),
        level=s.get("level", 0.95), workers=snakemake.threads, reports=s.get("reports", False),
        name=snakemake.wildcards.study, diagnosis_settings=snakemake.params.diagnosis,
        progress=sys.stderr,
    )
    logging.getLogger("skinsuction.cohort").info(
        "%d measurements, %d errors, %.1f s", result["measurements"], result["errors"],
        result["seconds"])
