"""Rule simulate_ray_bundle: the FE rays of one (model, probe, X1h/X1d) of the scale-free space."""

from skinsuction.jobs import job

with job(snakemake.log[0], threads=snakemake.threads):
    from skinsuction.space import compute_bundle

    compute_bundle(
        snakemake.params.rays,
        snakemake.output.bundle,
        pressures_mbar=snakemake.params.pressures,
        mesh=dict(snakemake.params.mesh),
        fallback=[dict(f) for f in snakemake.params.fallback],
        metadata={"bundle_id": snakemake.wildcards.bundle,
                  "source_hash": {"model": snakemake.params.code}},
    )
