"""FE suction curves of the grids, a row per job (shared by all spaces and figures)."""


rule simulate_row:
    """The FE curves of one row of the grids: one probe, bottom, X1d and layers, every
    X1h that a space or Figure 3 asks for there (a failed point is written as failed)."""
    output:
        curves="results/curves/{row}.parquet",
    log:
        "logs/simulate/{row}.log",
    benchmark:
        "results/benchmarks/simulate/{row}.tsv"
    params:
        # a change of any of these reruns the FE jobs (Snakemake's params trigger)
        points=lambda w: ROWS[w.row],
        pressures=PRESSURES,
        mesh=config["mesh"],
        fallback=config["mesh_fallback"],
        # the model, the point adapter and the curve format
        code=code_hash(*FE_CODE),
    threads: 1
    resources:
        mem_mb=2000,
        runtime=120,
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/simulate_row.py"
