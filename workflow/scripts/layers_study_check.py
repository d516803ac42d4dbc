"""Rule layers_study_check: the synthetic study of own layers against its truth."""

from skinsuction.jobs import job

with job(snakemake.log[0]):
    import json

    import pandas as pd

    from skinsuction.evaluation import (LayersStudyDesign, layers_study_check,
                                        layers_study_markdown)
    from skinsuction.jobs import write_table
    from skinsuction.results import write_text

    check = layers_study_check(pd.read_parquet(snakemake.input.curves),
                               pd.read_csv(snakemake.input.truth))
    seconds = json.loads(open(snakemake.input.study, encoding="utf-8").read()).get("seconds")
    rows = [{"table": "per_measurement", **r} for r in check["per_measurement"]] + \
        [{"table": "groups", **r} for r in check["groups"]]
    write_table(pd.DataFrame(rows), snakemake.output.table)
    write_text(snakemake.output.summary, layers_study_markdown(
        check, LayersStudyDesign.from_config(snakemake.params.design), seconds))
