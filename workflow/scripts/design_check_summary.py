"""Rule design_check: the rows of every skin and design, and the predicted against the
realised (intervals, detectability, the naming rate against its ceiling)."""

from skinsuction.jobs import atomic_output, job, write_table

with job(snakemake.log[0], threads=1):
    import pandas as pd

    from skinsuction.design import check_summary

    s = snakemake.params.settings
    rows = pd.concat([pd.read_csv(f) for f in snakemake.input.rows], ignore_index=True)
    write_table(rows, snakemake.output.rows)
    given = ", ".join(f"{k} ± {v:g} mm" for k, v in (s.get("given") or {}).items())
    lines = ["# Designs: predicted against realised", "",
             f"{s.get('skins', 60)} skins of the box (seed {s.get('seed', 1)}), FE virtual "
             f"experiments with 2 µm noise read at 0.01 mm, diagnosed"
             + (f"; given {given} (its true value in each file's header)" if given else "")
             + ".", "", "```", *check_summary(rows, tuple(s.get("causes", ()))), "```", ""]
    with atomic_output(snakemake.output.summary) as tmp:
        tmp.write_text("\n".join(lines), encoding="utf-8")
