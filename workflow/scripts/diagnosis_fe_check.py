"""Rule diagnosis_fe_check: direct FE runs at the parameters of a diagnosis (Figure 6)."""

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ[_var] = "1"

import json  # noqa: E402

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
    from skinsuction.diagnose import registry_from_config
    from skinsuction.diagnose._check import fe_check
    from skinsuction.space import write_table

    with open(snakemake.input.report, encoding="utf-8") as f:
        report = json.load(f)
    table = fe_check(report, mesh=dict(snakemake.params.mesh), bottom=snakemake.params.bottom,
                     causes=registry_from_config(snakemake.params.causes))
    write_table(table, snakemake.output.check)
