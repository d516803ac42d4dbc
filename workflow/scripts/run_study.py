"""Rule study: `skinsuction study` of one study of the config."""

import logging
from pathlib import Path

from skinsuction.jobs import job

with job(snakemake.log[0], threads=snakemake.threads):
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
