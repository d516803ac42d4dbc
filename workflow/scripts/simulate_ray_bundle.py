"""Rule simulate_ray_bundle: the FE rays of one (model, probe, X1h/X1d) of the scale-free space."""

# One job per core: the pools must be limited before NumPy is imported (the
# Snakemake preamble does not import it; skinsuction's __init__ is lazy).
from skinsuction._threads import limit_threads

limit_threads(snakemake.threads)

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
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
