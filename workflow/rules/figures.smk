"""Every figure rule: rule -> thin script -> one package function.

Included last by the Snakefile: a figure rule of a config section exists when
that section does (scale_free_space, identification, diagnosis), and reads the
settings its stage file (scale_free.smk, paper.smk, diagnose.smk) validated.
"""


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
        points=FIG3_POINTS,
        code=code_hash("figures", *SPACE_CODE),
    threads: 1
    resources:
        mem_mb=2000,
        runtime=10,
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/fig3_boundary_conditions.py"


# ------------------------------------------------------- the scale-free space
if "scale_free_space" in config:

    rule scale_free_coverage:
        input:
            spaces=SF_SPACES,
        output:
            table=report(
                "results/tables/scale_free_coverage.csv",
                caption="../report/scale_free_coverage.rst",
                category="Simulated spaces",
                labels={"space": "scale_free", "table": "coverage frontier"},
            ),
            png=report(
                "results/figures/scale_free_coverage.png",
                caption="../report/scale_free_coverage.rst",
                category="Simulated spaces",
                labels={"space": "scale_free", "figure": "coverage frontier"},
            ),
            pdf="results/figures/scale_free_coverage.pdf",
        log:
            "logs/scale_free/coverage.log",
        params:
            code=code_hash("figures", *SPACE_CODE),
        threads: 1
        resources:
            mem_mb=2000,
            runtime=10,
        conda:
            "../envs/skinsuction.yaml"
        script:
            "../scripts/scale_free_coverage.py"


# ---------------------------------------------- the paper's identification study
if "identification" in config:

    rule fig4_single_probe:
        input:
            runs="results/identification/single_probe_runs.csv",
        output:
            png=report(
                "results/figures/fig4_single_probe.png",
                caption="../report/fig4.rst",
                category="Figures",
                labels={"figure": "4", "format": "png"},
            ),
            pdf=report(
                "results/figures/fig4_single_probe.pdf",
                caption="../report/fig4.rst",
                category="Figures",
                labels={"figure": "4", "format": "pdf"},
            ),
            table=report(
                "results/tables/fig4_single_probe.csv",
                caption="../report/fig4.rst",
                category="Tables",
                labels={"table": "Figure 4"},
            ),
        log:
            "logs/figures/fig4_single_probe.log",
        params:
            target=ID["target"],
            success_tolerance=ID["success_tolerance"],
            code=ID_FIG_CODE,
        threads: 1
        resources:
            mem_mb=2000,
            runtime=10,
        conda:
            "../envs/skinsuction.yaml"
        script:
            "../scripts/fig4_single_probe.py"


    rule fig4b_cost_landscape:
        input:
            space=ID_SPACE,
            curves=ID_CURVES,
        output:
            png=report(
                "results/figures/fig4b_cost_landscape.png",
                caption="../report/fig4b.rst",
                category="Figures",
                labels={"figure": "4b", "format": "png"},
            ),
            pdf=report(
                "results/figures/fig4b_cost_landscape.pdf",
                caption="../report/fig4b.rst",
                category="Figures",
                labels={"figure": "4b", "format": "pdf"},
            ),
            table=report(
                "results/tables/fig4b_cost_landscape.csv",
                caption="../report/fig4b.rst",
                category="Tables",
                labels={"table": "Figure 4b"},
            ),
            landscape="results/identification/fig4b_landscape.parquet",
        log:
            "logs/figures/fig4b_cost_landscape.log",
        params:
            settings=ID,
            code=ID_FIG_CODE,
        threads: 1
        resources:
            mem_mb=3000,
            runtime=10,
        conda:
            "../envs/skinsuction.yaml"
        script:
            "../scripts/fig4b_cost_landscape.py"


    rule fig7_alpha:
        input:
            runs="results/identification/alpha_sweep_runs.csv",
        output:
            png=report(
                "results/figures/fig7_alpha.png",
                caption="../report/fig7.rst",
                category="Figures",
                labels={"figure": "7", "format": "png"},
            ),
            pdf=report(
                "results/figures/fig7_alpha.pdf",
                caption="../report/fig7.rst",
                category="Figures",
                labels={"figure": "7", "format": "pdf"},
            ),
            table=report(
                "results/tables/fig7_alpha.csv",
                caption="../report/fig7.rst",
                category="Tables",
                labels={"table": "Figure 7"},
            ),
            threshold=report(
                "results/tables/fig7_alpha_threshold.csv",
                caption="../report/fig7.rst",
                category="Tables",
                labels={"table": "Figure 7, alpha threshold"},
            ),
        log:
            "logs/figures/fig7_alpha.log",
        params:
            target=ID["target"],
            success_tolerance=ID["success_tolerance"],
            code=ID_FIG_CODE,
        threads: 1
        resources:
            mem_mb=2000,
            runtime=10,
        conda:
            "../envs/skinsuction.yaml"
        script:
            "../scripts/fig7_alpha.py"


    rule fig8_ratio:
        input:
            space=ID_SPACE,
            curves=ID_CURVES,
            runs="results/identification/ratio_runs.csv",
        output:
            png=report(
                "results/figures/fig8_ratio.png",
                caption="../report/fig8.rst",
                category="Figures",
                labels={"figure": "8", "format": "png"},
            ),
            pdf=report(
                "results/figures/fig8_ratio.pdf",
                caption="../report/fig8.rst",
                category="Figures",
                labels={"figure": "8", "format": "pdf"},
            ),
            table=report(
                "results/tables/fig8_ratio.csv",
                caption="../report/fig8.rst",
                category="Tables",
                labels={"table": "Figure 8"},
            ),
            ratio_curves="results/tables/fig8_ratio_curves.csv",
        log:
            "logs/figures/fig8_ratio.log",
        params:
            settings=ID,
            code=ID_FIG_CODE,
        threads: 1
        resources:
            mem_mb=2000,
            runtime=10,
        conda:
            "../envs/skinsuction.yaml"
        script:
            "../scripts/fig8_ratio.py"


# ------------------------------------------------------------- the diagnosis
if "diagnosis" in config:

    rule fig5_measured_identifications:
        input:
            measured=DG_MEASURED[DG["figure5"]["measured"]],
            space=f"results/simulated_space/{DG['figure5']['space']}.parquet",
        output:
            png=report(
                "results/figures/fig5_measured_identifications.png",
                caption="../report/fig5.rst",
                category="Figures",
                labels={"figure": "5", "format": "png"},
            ),
            pdf=report(
                "results/figures/fig5_measured_identifications.pdf",
                caption="../report/fig5.rst",
                category="Figures",
                labels={"figure": "5", "format": "pdf"},
            ),
            table="results/tables/fig5_measured_identifications.csv",
            runs="results/diagnosis/fig5_runs.csv",
        log:
            "logs/figures/fig5_measured_identifications.log",
        benchmark:
            "results/benchmarks/figures/fig5_measured_identifications.tsv"
        params:
            settings=DG["figure5"],
            code=DG_FIG_CODE,
        threads: 1
        resources:
            mem_mb=2000,
            runtime=30,
        conda:
            "../envs/skinsuction.yaml"
        script:
            "../scripts/fig5_measured_identifications.py"


    rule fig6_measured_vs_simulated:
        input:
            report=f"results/diagnosis/{DG['figure6']['measured']}/report.json",
            check=f"results/diagnosis/{DG['figure6']['measured']}/fe_check.csv",
        output:
            png=report(
                "results/figures/fig6_measured_vs_simulated.png",
                caption="../report/fig6.rst",
                category="Figures",
                labels={"figure": "6", "format": "png"},
            ),
            pdf=report(
                "results/figures/fig6_measured_vs_simulated.pdf",
                caption="../report/fig6.rst",
                category="Figures",
                labels={"figure": "6", "format": "pdf"},
            ),
            table="results/tables/fig6_measured_vs_simulated.csv",
        log:
            "logs/figures/fig6_measured_vs_simulated.log",
        params:
            code=DG_FIG_CODE,
        threads: 1
        resources:
            mem_mb=2000,
            runtime=10,
        conda:
            "../envs/skinsuction.yaml"
        script:
            "../scripts/fig6_measured_vs_simulated.py"


    if "confusion" in DG:
        DIAGNOSIS_OUTPUTS += [
            "results/figures/detectability_map.png",
            "results/tables/diagnosis_confusion_detectable.csv",
        ]

        # the draws in shards of every n-th draw, one thread each: Snakemake packs them
        # beside the other jobs (one two-core job ran alone at the study's end), a
        # cluster runs them side by side; a process a draw would cost its start-up each
        CONFUSION_SHARDS = int(DG["confusion"].get("shards", 5))

        rule detectability_draws:
            """Every n-th draw of the diagnosis over the physiological domain, from the j-th."""
            input:
                spaces=SF_SPACES,
            output:
                rows="results/diagnosis/confusion_draws/shard{shard}.csv",
            wildcard_constraints:
                shard="[0-9]+",
            log:
                "logs/diagnosis/detectability_draws/shard{shard}.log",
            benchmark:
                "results/benchmarks/diagnosis/detectability_draws/shard{shard}.tsv"
            params:
                per_cause=DG["confusion"]["per_cause"],
                seed=DG["confusion"].get("seed", 1000),
                shards=CONFUSION_SHARDS,
                decision=DG.get("decision", {}),
                fit=DG.get("fit", {}),
                code=code_hash("evaluation", "diagnose", "identify", "model", *SPACE_CODE),
            threads: 1
            resources:
                mem_mb=2000,
                runtime=60,
            conda:
                "../envs/skinsuction.yaml"
            script:
                "../scripts/detectability_draws.py"

        rule detectability_map:
            """Diagnosis over the physiological domain: confusion matrix and detectability map."""
            input:
                spaces=SF_SPACES,
                rows=expand("results/diagnosis/confusion_draws/shard{shard}.csv",
                            shard=range(CONFUSION_SHARDS)),
            output:
                draws="results/diagnosis/confusion_draws.csv",
                matrix=report(
                    "results/tables/diagnosis_confusion_detectable.csv",
                    caption="../report/detectability.rst",
                    category="Diagnosis",
                    labels={"table": "confusion matrix (detectable draws)"},
                ),
                rates="results/tables/diagnosis_confusion_rates.csv",
                png=report(
                    "results/figures/detectability_map.png",
                    caption="../report/detectability.rst",
                    category="Diagnosis",
                    labels={"figure": "detectability map"},
                ),
                pdf="results/figures/detectability_map.pdf",
            log:
                "logs/diagnosis/detectability_map.log",
            params:
                causes=[n for n in SF_MODELS if n != BASELINE],
                code=code_hash("evaluation", "diagnose", "figures"),
            threads: 1
            resources:
                mem_mb=2000,
                runtime=10,
            conda:
                "../envs/skinsuction.yaml"
            script:
                "../scripts/confusion_summary.py"

    if "published_ranges" in DG:
        # not in the default target: 955 FE mode-1 solves, 34 CPU-min, twice the rest of
        # the study's 15-minute budget (`snakemake --cores 2 published_ranges`)

        rule published_ranges:
            """Target: which skins reach the published Cutometer values of the face: FE
            mode-1 curves of creep alone and of creep with a stiffening dermis."""
            output:
                draws="results/tables/published_ranges.csv",
                summary=report(
                    "results/tables/published_ranges.md",
                    caption="../report/published_ranges.rst",
                    category="Diagnosis",
                    labels={"table": "published Cutometer ranges"},
                ),
                png=report(
                    "results/figures/published_ranges.png",
                    caption="../report/published_ranges.rst",
                    category="Diagnosis",
                    labels={"figure": "published Cutometer ranges"},
                ),
                pdf="results/figures/published_ranges.pdf",
            log:
                "logs/diagnosis/published_ranges.log",
            benchmark:
                "results/benchmarks/diagnosis/published_ranges.tsv"
            params:
                settings=DG["published_ranges"],
                mesh=config.get("mesh", {}),
                code=code_hash("evaluation", "viscoelastic", "model", "measured", "figures"),
            threads: 2
            resources:
                mem_mb=3000,
                runtime=60,
            conda:
                "../envs/skinsuction.yaml"
            script:
                "../scripts/published_ranges.py"

    if "time_effects_confusion" in DG:
        # Opt-in (not in the default target): FE time solves and a diagnosis effect by
        # effect per draw and design, about 15 min on 2 cores for 10 per class.

        rule time_effects_confusion:
            """Single and paired effects in Cutometer time curves, named effect by effect:
            FE mode-1 draws of each class under each design, diagnosed."""
            output:
                draws="results/tables/time_effects_confusion.csv",
                summary=report(
                    "results/tables/time_effects_confusion.md",
                    caption="../report/time_effects_confusion.rst",
                    category="Diagnosis",
                    labels={"table": "effects in time curves"},
                ),
                png=report(
                    "results/figures/time_effects_confusion.png",
                    caption="../report/time_effects_confusion.rst",
                    category="Diagnosis",
                    labels={"figure": "effects in time curves"},
                ),
                pdf="results/figures/time_effects_confusion.pdf",
            log:
                "logs/diagnosis/time_effects_confusion.log",
            benchmark:
                "results/benchmarks/diagnosis/time_effects_confusion.tsv"
            params:
                settings=DG["time_effects_confusion"],
                code=code_hash("evaluation", "diagnose", "identify", "viscoelastic", "model",
                               "measured", "figures", *SPACE_CODE),
            threads: 2
            resources:
                mem_mb=3000,
                runtime=60,
            conda:
                "../envs/skinsuction.yaml"
            script:
                "../scripts/time_effects_confusion.py"

    if "ramp_effects_confusion" in DG:
        # Opt-in (not in the default target): FE ramps and a diagnosis with the pair
        # spaces per draw and design (two diagnoses: the noisy curves and, for the
        # detectability, the noise-free ones).

        rule ramp_effects_confusion:
            """Single and paired effects in pressure ramps: FE draws of each class under
            each design (2 + 6 and 4 + 8 mm, to 100-500 mbar), diagnosed with the pair
            spaces."""
            output:
                draws="results/tables/ramp_effects_confusion.csv",
                summary=report(
                    "results/tables/ramp_effects_confusion.md",
                    caption="../report/ramp_effects_confusion.rst",
                    category="Diagnosis",
                    labels={"table": "effects in ramps"},
                ),
                png=report(
                    "results/figures/ramp_effects_confusion.png",
                    caption="../report/ramp_effects_confusion.rst",
                    category="Diagnosis",
                    labels={"figure": "effects in ramps"},
                ),
                pdf="results/figures/ramp_effects_confusion.pdf",
            log:
                "logs/diagnosis/ramp_effects_confusion.log",
            benchmark:
                "results/benchmarks/diagnosis/ramp_effects_confusion.tsv"
            params:
                settings=DG["ramp_effects_confusion"],
                code=code_hash("evaluation", "diagnose", "identify", "model", "measured",
                               "figures", *SPACE_CODE),
            threads: 2
            resources:
                mem_mb=3000,
                runtime=60,
            conda:
                "../envs/skinsuction.yaml"
            script:
                "../scripts/ramp_effects_confusion.py"

    if "confusion_given_layers" in DG:
        # Opt-in (not in the default target): every draw has its own dermis, and every
        # candidate cause's rays are solved on demand at it and at +-1 sd of it (cut to
        # an X1h/X1d window around the neo-Hookean fit), some 15 CPU-min a draw: one job
        # a draw, so a cluster runs them side by side and a stopped run keeps its draws.
        CGL = DG["confusion_given_layers"]
        # the hypodermis is given too where its sd is set: then it is no cause either
        CGL_GIVEN = ("t_d", "t_h") if CGL.get("hypodermis_sd_mm") is not None else ("t_d",)
        CGL_TRUTHS = ["none"] + [n for n, c in SF_CAUSES.items() if c.keyword not in CGL_GIVEN]
        CGL_DRAWS = [f"{truth}_{int(CGL.get('seed', 1000)) + 100000 * k + i}"
                     for k, truth in enumerate(CGL_TRUTHS) for i in range(CGL["per_cause"])]
        CGL_DIR = "results/diagnosis/confusion_given_layers"

        rule confusion_given_layers_draw:
            """One virtual experiment with its dermis given: FE curves, diagnosis, verdict."""
            input:
                spaces=SF_SPACES,
            output:
                row=f"{CGL_DIR}/{{draw}}.csv",
            wildcard_constraints:
                draw="[a-z_]+_[0-9]+",
            log:
                "logs/diagnosis/confusion_given_layers/{draw}.log",
            benchmark:
                "results/benchmarks/diagnosis/confusion_given_layers/{draw}.tsv"
            params:
                domain={
                    "given_dermis_thickness": {
                        "range": CGL.get("dermis_range_mm", [0.5, 2.5]),
                        "sd": CGL.get("dermis_sd_mm", 0.1),
                    },
                    "given_hypodermis_thickness": {
                        "range": CGL.get("hypodermis_range_mm", [0.5, 10.0]),
                        "sd": CGL.get("hypodermis_sd_mm"),
                    },
                    "probe_pairs": CGL.get("probe_pairs", [[2, 6], [4, 8]]),
                },
                on_demand_dir="results/simulated_space/on_demand",
                decision=DG.get("decision", {}),
                fit=DG.get("fit", {}),
                code=code_hash("evaluation", "diagnose", "identify", "model", *SPACE_CODE),
            threads: 1
            resources:
                mem_mb=2000,
                runtime=120,
            conda:
                "../envs/skinsuction.yaml"
            script:
                "../scripts/confusion_draw.py"

        rule confusion_given_layers:
            """The diagnosis with the dermis thickness given: confusion over the draws."""
            input:
                spaces=SF_SPACES,
                rows=expand(f"{CGL_DIR}/{{draw}}.csv", draw=CGL_DRAWS),
            output:
                draws="results/diagnosis/confusion_given_layers_draws.csv",
                matrix=report(
                    "results/tables/diagnosis_confusion_given_layers_detectable.csv",
                    caption="../report/detectability_given_layers.rst",
                    category="Diagnosis",
                    labels={"table": "confusion matrix, dermis given (detectable draws)"},
                ),
                rates="results/tables/diagnosis_confusion_given_layers_rates.csv",
                png="results/figures/detectability_given_layers.png",
                pdf="results/figures/detectability_given_layers.pdf",
            log:
                "logs/diagnosis/confusion_given_layers.log",
            params:
                causes=CGL_TRUTHS[1:],
                code=code_hash("evaluation", "diagnose", "figures"),
            threads: 1
            resources:
                mem_mb=2000,
                runtime=10,
            conda:
                "../envs/skinsuction.yaml"
            script:
                "../scripts/confusion_summary.py"
