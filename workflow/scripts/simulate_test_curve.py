"""Rule simulate_test_curve: one FE suction curve at one point (off the grid)."""

from skinsuction.jobs import job

with job(snakemake.log[0], threads=snakemake.threads):
    from skinsuction.space import compute_point

    compute_point(
        snakemake.wildcards.point,
        snakemake.output.curve,
        pressures_mbar=snakemake.params.pressures,
        mesh=dict(snakemake.params.mesh),
        fallback=snakemake.params.fallback,
        metadata={"source_hash": {"model": snakemake.params.code}},
    )
