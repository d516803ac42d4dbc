"""One FE suction curve per grid point (shared by all spaces and figures)."""


rule simulate_point:
    output:
        curve="results/curves/{point}.parquet",
    log:
        "logs/simulate/{point}.log",
    benchmark:
        "results/benchmarks/simulate/{point}.tsv"
    params:
        # a change of any of these reruns the FE jobs (Snakemake's params trigger)
        pressures=PRESSURES,
        mesh=config["mesh"],
        fallback=config["mesh_fallback"],
        # the model, the point adapter and the curve format
        code=code_hash(*FE_CODE),
    threads: 1
    resources:
        mem_mb=2000,
        runtime=30,
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/simulate_point.py"
