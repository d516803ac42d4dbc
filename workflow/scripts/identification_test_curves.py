"""Rule identification_test_curves: FE and interpolated curves at the test point."""

from skinsuction.jobs import job

with job(snakemake.log[0], threads=snakemake.threads):
    from skinsuction.paper import make_test_curves

    t = snakemake.params.target
    make_test_curves(
        snakemake.input.space,
        snakemake.input.fe,
        snakemake.output.curves,
        target=(t["x1d"], t["x1h"]),
        bottom=snakemake.params.bottom,
    )
