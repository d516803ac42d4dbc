"""Rule diagnosis_fe_check: direct FE runs at the parameters of a diagnosis (Figure 6)."""

# BLAS/OpenMP pools sized to the job's threads, before NumPy is imported (the
# Snakemake preamble does not import it; skinsuction's __init__ is lazy).
from skinsuction._threads import limit_threads

limit_threads(snakemake.threads)

import json  # noqa: E402

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
    from skinsuction.diagnose import registry_from_config
    from skinsuction.evaluation import fe_check
    from skinsuction._files import write_table

    with open(snakemake.input.report, encoding="utf-8") as f:
        report = json.load(f)
    table = fe_check(report, mesh=dict(snakemake.params.mesh), bottom=snakemake.params.bottom,
                     causes=registry_from_config(snakemake.params.causes))
    write_table(table, snakemake.output.check)
