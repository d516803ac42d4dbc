"""Rules simulate_ray_bundle and simulate_geometry_bundle: a bundle of FE rays of the scale-free space."""

from skinsuction.jobs import job

with job(snakemake.log[0], threads=snakemake.threads):
    from skinsuction.space import compute_bundle

    compute_bundle(
        snakemake.params.rays,
        snakemake.output.bundle,
        pressures_mbar=snakemake.params.pressures,
        mesh=dict(snakemake.params.mesh),
        fallback=[dict(f) for f in snakemake.params.fallback],
        fallback_below_mbar=getattr(snakemake.params, "fallback_below", None),
        metadata={"bundle_id": getattr(snakemake.params, "bundle", None)
                  or snakemake.wildcards.bundle,
                  "source_hash": {"model": snakemake.params.code}},
    )
