# Identification of skin layer elasticity from suction tests: the study workflow.
#
#   snakemake --cores 2                               # the paper's study
#   snakemake --cores 2 --configfile config/ci.yaml   # coarse, a few minutes
#   snakemake --profile profiles/slurm                # on a SLURM cluster
#   snakemake --report report.html                    # figures with captions
#
# config -> FE curves (one job per grid point) -> simulated spaces -> figures
#        -> FE ray bundles -> the scale-free space (identify/diagnose default) + coverage
#           + its check against the default space shipped with the package
#        -> identifications (Figures 4, 4b, 7, 8, timing and optimiser tables)
#        -> diagnoses of measured files on the scale-free space (reports, Figures 5, 6)
#        -> whole studies: every curve identified with intervals and diagnosed
#        -> planning a measurement: the probes and suction that answer a question


include: "workflow/rules/common.smk"
include: "workflow/rules/simulate.smk"
include: "workflow/rules/space.smk"


if "scale_free_space" in config:

    include: "workflow/rules/scale_free.smk"


if "identification" in config:

    include: "workflow/rules/paper.smk"


if "diagnosis" in config:

    include: "workflow/rules/diagnose.smk"


if "studies" in config:

    include: "workflow/rules/study.smk"


if "design" in config:

    include: "workflow/rules/design.smk"


include: "workflow/rules/figures.smk"


report: "workflow/report/workflow.rst"


localrules:
    all,


rule all:
    input:
        final_outputs(),
        SCALE_FREE_OUTPUTS if "scale_free_space" in config else [],
        SHIPPED_CHECK_OUTPUTS if "scale_free_space" in config else [],
        IDENTIFICATION_OUTPUTS if "identification" in config else [],
        DIAGNOSIS_OUTPUTS if "diagnosis" in config else [],
        STUDY_OUTPUTS if "studies" in config else [],
        DESIGN_OUTPUTS if "design" in config else [],
    default_target: True
