"""Planning a measurement: which probes and suction answer a question (skinsuction design).

Included by the Snakefile when the configuration has a `design` section (it needs
`scale_free_space`: the spaces the predictions read; no FE run).

box of skins + candidate designs + the question + the scale-free space
  -> results/design/precision/{design.md, designs.csv, predictions.csv, design.json,
     precision.png} (in the default target: X1h to ±20 %)
  -> results/design/causes/...: the same with causes told apart (target design_causes)
"""

DESIGN = dict(config["design"])
if "scale_free_space" not in config:
    raise _config_error("design", "needs a scale_free_space section (the space it reads)")
DESIGN_CODE = code_hash("design", "diagnose", "figures", "evaluation", *SPACE_CODE)
DESIGN_FILES = {"markdown": "design.md", "designs": "designs.csv",
                "predictions": "predictions.csv", "record": "design.json",
                "figure": "precision.png"}
DESIGN_OUTPUTS = expand("results/design/precision/{file}", file=DESIGN_FILES.values())


localrules:
    design_causes,


rule design:
    """Every candidate design over the box's skins: precision, bounded fractions (and
    with the causes, detectability and attribution ceilings); the recommendation."""
    input:
        spaces=SF_SPACES,
    output:
        **{
            k: (
                report(
                    f"results/design/{{which}}/{f}",
                    caption="../report/design.rst",
                    category="Design",
                    labels={"question": "{which}", "file": f},
                )
                if k in ("markdown", "figure")
                else f"results/design/{{which}}/{f}"
            )
            for k, f in DESIGN_FILES.items()
        },
    log:
        "logs/design/{which}.log",
    benchmark:
        "results/benchmarks/design/{which}.tsv"
    params:
        settings=lambda w: design_settings(DESIGN, w.which),
        space_dir=lambda w, input: os.path.dirname(input.spaces[0]),
        code=DESIGN_CODE,
    wildcard_constraints:
        which="precision|causes",
    threads: 2
    resources:
        mem_mb=3000,
        runtime=60,
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/design.py"


rule design_causes:
    """Target: the designs with pre-tension, a thick hypodermis and stiffening told apart."""
    input:
        expand("results/design/causes/{file}", file=DESIGN_FILES.values()),
