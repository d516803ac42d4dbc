"""Diagnosis of measured curves (what the neo-Hookean model gets wrong, and why), Figures 5, 6.

Included by the Snakefile when the configuration has a `diagnosis` section (it
needs `scale_free_space`, scale_free.smk).

scale-free space (neo_hookean + one per cause: results/simulated_space/scale_free/)
  -> one diagnosis per measured file (results/diagnosis/<name>/report.json, .md, figures)
  -> direct FE runs at the diagnosed parameters (fe_check.csv) -> Figure 6
measured file + the paper's space -> 100 neo-Hookean identifications -> Figure 5
"""

DG = config["diagnosis"]
if "scale_free_space" not in config:
    raise _config_error("diagnosis", "needs a scale_free_space section (the space it reads)")
DG_MEASURED = dict(DG["measured"])
DG_TIME = dict(DG.get("time_curves") or {})
DG_CODE = code_hash("diagnose", "identify", *SPACE_CODE, "measured")
DG_FIG_CODE = code_hash("paper", "diagnose", "identify", "figures", *SPACE_CODE, "measured")

for _key in ("figure5", "figure6"):
    if DG[_key]["measured"] not in DG_MEASURED:
        raise _config_error(
            f"diagnosis.{_key}.measured",
            f"{DG[_key]['measured']!r} is not among diagnosis.measured ({', '.join(DG_MEASURED)})",
        )
if DG["figure5"]["space"] not in SPACE_POINTS:
    raise _config_error(
        "diagnosis.figure5.space",
        f"{DG['figure5']['space']!r} is not among spaces ({', '.join(SPACE_POINTS)})",
    )


wildcard_constraints:
    name="|".join(map(re.escape, DG_MEASURED)),


DIAGNOSIS_OUTPUTS = [
    *expand(
        "results/diagnosis/{name}/{file}",
        name=DG_MEASURED,
        file=["report.json", "report.md", "fit.png", "residuals.png", "gain.png"],
    ),
    "results/figures/fig5_measured_identifications.png",
    "results/figures/fig5_measured_identifications.pdf",
    "results/tables/fig5_measured_identifications.csv",
    "results/figures/fig6_measured_vs_simulated.png",
    "results/figures/fig6_measured_vs_simulated.pdf",
    "results/tables/fig6_measured_vs_simulated.csv",
    *expand("results/diagnosis/time/{tname}/{file}", tname=DG_TIME,
            file=["report.json", "report.md", "fit.png"]),
]


# The synthetic example of data/ is shipped, not made by the workflow (a rule
# producing a tracked file reruns whenever its code changes); remake it by hand
# with:  python -m skinsuction.evaluation.example data/example_suction_synthetic.csv


rule diagnose_measured:
    input:
        measured=lambda w: DG_MEASURED[w.name],
        spaces=SF_SPACES,
        pairs=pair_space_files,
    output:
        json=report(
            "results/diagnosis/{name}/report.json",
            caption="../report/diagnosis.rst",
            category="Diagnosis",
            labels={"measured": "{name}", "file": "report.json"},
        ),
        md="results/diagnosis/{name}/report.md",
        fit=report(
            "results/diagnosis/{name}/fit.png",
            caption="../report/diagnosis.rst",
            category="Diagnosis",
            labels={"measured": "{name}", "file": "fit"},
        ),
        residuals=report(
            "results/diagnosis/{name}/residuals.png",
            caption="../report/diagnosis.rst",
            category="Diagnosis",
            labels={"measured": "{name}", "file": "residuals"},
        ),
        gain=report(
            "results/diagnosis/{name}/gain.png",
            caption="../report/diagnosis.rst",
            category="Diagnosis",
            labels={"measured": "{name}", "file": "gain"},
        ),
    log:
        "logs/diagnosis/{name}.log",
    benchmark:
        "results/benchmarks/diagnosis/diagnose_{name}.tsv"
    params:
        decision=DG.get("decision", {}),
        fit=DG.get("fit", {}),
        code=DG_FIG_CODE,
        # rays of a probe or layers the space lacks, solved on demand, kept here
        on_demand_dir="results/simulated_space/on_demand",
    # a file with its own layers solves its causes' rays at them and at +-1 sd of a
    # given thickness: about 1 300 CPU-s for two probes, in this many processes
    threads: 2
    resources:
        mem_mb=3000,
        runtime=60,
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/diagnose_measured.py"


rule diagnosis_fe_check:
    input:
        report="results/diagnosis/{name}/report.json",
    output:
        check="results/diagnosis/{name}/fe_check.csv",
    log:
        "logs/diagnosis/{name}_fe_check.log",
    benchmark:
        "results/benchmarks/diagnosis/fe_check_{name}.tsv"
    params:
        mesh=SF_SPEC.mesh,
        bottom=SF_SPEC.bottom,
        causes=SF["causes"],
        code=code_hash("evaluation", "diagnose", *FE_RAY_CODE),
    threads: 1
    resources:
        mem_mb=2000,
        runtime=30,
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/diagnosis_fe_check.py"


rule diagnose_time_curves:
    """`skinsuction diagnose` of a time-curve file: viscoelastic creep or not."""
    input:
        measured=lambda w: DG_TIME[w.tname],
        spaces=SF_SPACES,
    output:
        json="results/diagnosis/time/{tname}/report.json",
        md="results/diagnosis/time/{tname}/report.md",
        fit=report(
            "results/diagnosis/time/{tname}/fit.png",
            caption="../report/diagnosis_time.rst",
            category="Diagnosis",
            labels={"time curves": "{tname}", "file": "fit"},
        ),
        pdf="results/diagnosis/time/{tname}/fit.pdf",
    log:
        "logs/diagnosis/time_{tname}.log",
    benchmark:
        "results/benchmarks/diagnosis/diagnose_time_{tname}.tsv"
    wildcard_constraints:
        tname="|".join(map(re.escape, DG_TIME)) or "(?!)",
    params:
        decision=DG.get("decision", {}),
        fit=DG.get("fit", {}),
        code=code_hash("diagnose", "identify", "viscoelastic", *SPACE_CODE, "measured"),
    threads: 1
    resources:
        mem_mb=2000,
        runtime=30,
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/diagnose_time_curves.py"
