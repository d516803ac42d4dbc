"""Rule simulate_ray: one FE ray of the diagnosis spaces (one curve at X1d = X1d_min)."""

# One job per core: the pools must be limited before NumPy is imported (the
# Snakemake preamble does not import it; skinsuction's __init__ is lazy).
from skinsuction._threads import limit_threads

limit_threads(snakemake.threads)

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
    from skinsuction.diagnose import compute_ray

    compute_ray(
        snakemake.wildcards.ray,
        snakemake.output.ray,
        pressures_mbar=snakemake.params.pressures,
        mesh=dict(snakemake.params.mesh),
        metadata={"source_hash": {"model": snakemake.params.code}},
    )
