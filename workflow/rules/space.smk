"""Assembly of the simulated spaces and their convergence tables."""


rule assemble_space:
    input:
        curves=space_curves,
    output:
        space="results/simulated_space/{space}.parquet",
    log:
        "logs/space/{space}.log",
    params:
        points=lambda w: SPACE_POINTS[w.space],
        code=code_hash(*SPACE_CODE),
    threads: 1
    resources:
        mem_mb=4000,
        runtime=20,
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/assemble_space.py"


rule convergence_table:
    input:
        space="results/simulated_space/{space}.parquet",
    output:
        table=report(
            "results/tables/{space}_convergence.csv",
            caption="../report/convergence.rst",
            category="Simulated spaces",
            labels={"space": "{space}", "table": "convergence"},
        ),
    log:
        "logs/space/{space}_convergence.log",
    params:
        code=code_hash(*SPACE_CODE),
    threads: 1
    resources:
        mem_mb=2000,
        runtime=10,
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/convergence_table.py"
