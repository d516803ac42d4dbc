"""Whole clinical studies: every measurement identified (with intervals) and diagnosed.

Included by the Snakefile when the configuration has a `studies` section (it
needs `scale_free_space`, scale_free.smk).

study folder or long CSV + the scale-free space
  -> results/studies/<study>/curves.parquet (one row per measurement), comparison.csv,
     summary.md, study.json and figures (distributions, paired changes, causes)
"""

STUDIES = dict(config["studies"])
if "scale_free_space" not in config:
    raise _config_error("studies", "needs a scale_free_space section (the space it reads)")
STUDY_CODE = code_hash(
    "cohort", "identify", "diagnose", "figures", "measured", "noise.py", *SPACE_CODE
)
STUDY_INPUTS = {name: study_files(s["path"]) for name, s in STUDIES.items()}
STUDY_FIGURES = ["distribution_x1d", "paired_x1d", "causes"]
STUDY_OUTPUTS = [
    *expand(
        "results/studies/{study}/{file}",
        study=STUDIES,
        file=["curves.parquet", "comparison.csv", "summary.md", "study.json"],
    ),
    *expand("results/studies/{study}/{fig}.png", study=STUDIES, fig=STUDY_FIGURES),
]


wildcard_constraints:
    study="|".join(map(re.escape, STUDIES)),


rule study:
    input:
        files=lambda w: STUDY_INPUTS[w.study],
        spaces=SF_SPACES,
        pairs=pair_space_files,
    output:
        curves="results/studies/{study}/curves.parquet",
        comparison=report(
            "results/studies/{study}/comparison.csv",
            caption="../report/study.rst",
            category="Studies",
            labels={"study": "{study}", "file": "group comparison"},
        ),
        summary="results/studies/{study}/summary.md",
        study="results/studies/{study}/study.json",
        figures=[
            report(
                f"results/studies/{{study}}/{fig}.png",
                caption="../report/study.rst",
                category="Studies",
                labels={"study": "{study}", "file": fig},
            )
            for fig in STUDY_FIGURES
        ],
    log:
        "logs/studies/{study}.log",
    benchmark:
        "results/benchmarks/studies/{study}.tsv"
    params:
        settings=lambda w: STUDIES[w.study],
        diagnosis=lambda w: {**DG.get("decision", {})} if "diagnosis" in config else {},
        space_dir=lambda w, input: os.path.dirname(input.spaces[0]),
        code=STUDY_CODE,
    threads: 2
    resources:
        mem_mb=4000,
        runtime=60,
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/run_study.py"
