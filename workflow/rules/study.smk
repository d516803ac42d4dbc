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

# the synthetic study of own layers (below) is a study too, but not in STUDY_OUTPUTS
LAYERS = config.get("layers_study")
LAYERS_INPUT = "results/studies_input/layers"
LAYERS_TRUTH = "results/studies_input/layers_truth.csv"
if LAYERS:
    STUDIES["layers"] = {**LAYERS, "path": LAYERS_INPUT}
    STUDY_INPUTS["layers"] = [LAYERS_INPUT]


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


# ------------------------------------------------- the synthetic study of own layers
# config.layers_study -> FE virtual experiments of subjects with their own layers
#   (results/studies_input/layers/, the truth beside it; rule make_layers_study)
#   -> skinsuction study (results/studies/layers/: the same files as any study)
#   -> against the truth (results/studies/layers/truth_check.md, .csv)
# Target layers_study; not in the default target (62 CPU-min to make, and the
# study itself is what is timed: results/benchmarks/studies/layers.tsv).


localrules:
    layers_study,


rule layers_study:
    """Target: the synthetic study of subjects with their own layers, against its truth."""
    input:
        "results/studies/layers/summary.md" if LAYERS else [],
        "results/studies/layers/truth_check.md" if LAYERS else [],


rule make_layers_study:
    """SYNTHETIC subjects with their own layers: a ramp and a mode-1 curve each (FE)."""
    output:
        folder=directory(LAYERS_INPUT),
        truth=LAYERS_TRUTH,
    log:
        "logs/studies/make_layers_study.log",
    benchmark:
        "results/benchmarks/studies/make_layers_study.tsv"
    params:
        design=lambda w: {**(LAYERS or {}).get("generate", {}),
                          "fallback": list(config["scale_free_space"].get("mesh_fallback", []))},
        code=code_hash("evaluation", *FE_RAY_CODE),
    threads: 2
    resources:
        mem_mb=4000,
        runtime=120,
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/make_layers_study.py"


rule layers_study_check:
    """The study's estimates and verdicts against the truth of its subjects."""
    input:
        curves="results/studies/layers/curves.parquet",
        study="results/studies/layers/study.json",
        truth=LAYERS_TRUTH,
    output:
        table="results/studies/layers/truth_check.csv",
        summary=report(
            "results/studies/layers/truth_check.md",
            caption="../report/layers_study.rst",
            category="Studies",
            labels={"study": "layers", "file": "against the truth"},
        ),
    log:
        "logs/studies/layers_study_check.log",
    params:
        design=lambda w: (LAYERS or {}).get("generate", {}),
        code=code_hash("evaluation"),
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/layers_study_check.py"
