"""Figures of the paper: rule -> script -> one package function."""


rule fig3_boundary_conditions:
    input:
        curves=fig3_curves,
    output:
        png=report(
            "results/figures/fig3_boundary_conditions.png",
            caption="../report/fig3.rst",
            category="Figures",
            labels={"figure": "3", "format": "png"},
        ),
        pdf=report(
            "results/figures/fig3_boundary_conditions.pdf",
            caption="../report/fig3.rst",
            category="Figures",
            labels={"figure": "3", "format": "pdf"},
        ),
        table="results/tables/fig3_boundary_conditions.csv",
    log:
        "logs/figures/fig3_boundary_conditions.log",
    params:
        pressure_mbar=FIG3_PRESSURE,
        code=code_hash("figures", *SPACE_CODE),
    threads: 1
    resources:
        mem_mb=2000,
        runtime=10,
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/fig3_boundary_conditions.py"
