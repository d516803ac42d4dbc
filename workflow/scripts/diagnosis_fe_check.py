"""Rule diagnosis_fe_check: direct FE runs at the parameters of a diagnosis (Figure 6)."""

import json

from skinsuction.jobs import job, write_table

with job(snakemake.log[0], threads=snakemake.threads):
    from skinsuction.diagnose import registry_from_config
    from skinsuction.evaluation import fe_check

    with open(snakemake.input.report, encoding="utf-8") as f:
        report = json.load(f)
    table = fe_check(report, mesh=dict(snakemake.params.mesh), bottom=snakemake.params.bottom,
                     causes=registry_from_config(snakemake.params.causes))
    write_table(table, snakemake.output.check)
