"""Rule simulate_point: one FE suction curve at one grid point."""

# One job per core: the pools must be limited before NumPy is imported (the
# Snakemake preamble does not import it; skinsuction's __init__ is lazy).
from skinsuction._threads import limit_threads

limit_threads(snakemake.threads)

from skinsuction.provenance import log_to_file  # noqa: E402

with log_to_file(snakemake.log[0]):
    from skinsuction.space import compute_point

    compute_point(
        snakemake.wildcards.point,
        snakemake.output.curve,
        pressures_mbar=snakemake.params.pressures,
        mesh=dict(snakemake.params.mesh),
        fallback=snakemake.params.fallback,
        metadata={"source_hash": {"model": snakemake.params.code}},
    )
