"""Rule simulate_row: the FE curves of one row of the grids, in one file."""

from skinsuction.jobs import job

with job(snakemake.log[0], threads=snakemake.threads):
    from skinsuction.space import compute_points

    compute_points(
        snakemake.params.points,
        snakemake.output.curves,
        pressures_mbar=snakemake.params.pressures,
        mesh=dict(snakemake.params.mesh),
        fallback=snakemake.params.fallback,
        metadata={"source_hash": {"model": snakemake.params.code}},
    )
