"""Planning a measurement: which probes and suction answer a question (skinsuction design).

Included by the Snakefile when the configuration has a `design` section (it needs
`scale_free_space`: the spaces the predictions read; no FE run).

box of skins + candidate designs + the question + the scale-free space
  -> results/design/precision/{design.md, designs.csv, predictions.csv, design.json,
     precision.png} (in the default target: X1h to ±20 %)
  -> results/design/causes/...: the same with causes told apart (target design_causes)
design.check: designs x skins of the box, each measured by FE virtual experiments and
  diagnosed (one job a skin: rows/<design>/<skin>.csv)
  -> results/design/check/{rows.csv, summary.md} (target design_check, not in the
     default target: about 2 CPU-min a skin and design)
"""

DESIGN = dict(config["design"])
if "scale_free_space" not in config:
    raise _config_error("design", "needs a scale_free_space section (the space it reads)")
DESIGN_CODE = code_hash("design", "diagnose", "figures", "evaluation", *SPACE_CODE)
DESIGN_FILES = {"markdown": "design.md", "designs": "designs.csv",
                "predictions": "predictions.csv", "record": "design.json",
                "figure": "precision.png"}
DESIGN_OUTPUTS = expand("results/design/precision/{file}", file=DESIGN_FILES.values())


DCHECK = dict(DESIGN.get("check") or {})
DCHECK_DIR = "results/design/check"
DCHECK_ROWS = [
    f"{DCHECK_DIR}/rows/{d}/{i}.csv"
    for d in DCHECK.get("designs", [])
    for i in range(DCHECK.get("skins", 60))
]


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


rule design_check_skin:
    """One skin of the box and one design: the prediction, then FE virtual experiments
    of the skin (and of it with each cause added) diagnosed as a user runs diagnose."""
    input:
        spaces=SF_SPACES,
    output:
        row=f"{DCHECK_DIR}/rows/{{design}}/{{skin}}.csv",
    wildcard_constraints:
        design=r"[2468](\+[2468])*@[0-9]+",
        skin="[0-9]+",
    log:
        "logs/design/check/{design}/{skin}.log",
    benchmark:
        "results/benchmarks/design/check/{design}/{skin}.tsv"
    params:
        settings=DCHECK,
        box=DESIGN.get("box"),
        noise_um=DESIGN.get("noise_um", 2.0),
        resolution_mm=DESIGN.get("resolution_mm", 0.01),
        on_demand_dir="results/simulated_space/on_demand",
        code=code_hash("design", "diagnose", "evaluation", "model", *SPACE_CODE),
    threads: 1
    resources:
        mem_mb=3000,
        runtime=60,
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/design_check_skin.py"


rule design_check:
    """Target: the designs' predictions against the diagnoses of FE virtual experiments."""
    input:
        rows=DCHECK_ROWS,
    output:
        rows=f"{DCHECK_DIR}/rows.csv",
        summary=report(
            f"{DCHECK_DIR}/summary.md",
            caption="../report/design_check.rst",
            category="Design",
            labels={"question": "check", "file": "summary.md"},
        ),
    log:
        "logs/design/check.log",
    params:
        settings=DCHECK,
        code=code_hash("design", "evaluation"),
    threads: 1
    resources:
        mem_mb=2000,
        runtime=10,
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/design_check_summary.py"
