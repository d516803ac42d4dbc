"""The paper's identification study (sections 3.2-3.3): test curves, runs, tables.

Included by the Snakefile when the configuration has an `identification` section.

space + direct FE runs at the test point -> test curves -> runs of 100
identifications per case (results/identification/) -> the timing and optimiser tables here, Figures 4, 4b, 7, 8 in figures.smk.
Every rule carries the hash of the package code it runs (params.code), so a
change in paper/, identify/ or figures/ reruns exactly the rules that use it.
"""

ID = config["identification"]

if ID["space"] not in SPACE_POINTS:
    raise _config_error(
        "identification.space",
        f"{ID['space']!r} is not among spaces ({', '.join(SPACE_POINTS)})",
    )
_ID_PROBES = expand_axis(config["spaces"][ID["space"]]["probes_mm"])
if not {2.0, 6.0} <= set(_ID_PROBES):
    raise _config_error(
        "identification.space",
        f"space {ID['space']!r} needs the 2 and 6 mm probes, has {_ID_PROBES}",
    )
if ID["bottom"] not in expand_axis(config["spaces"][ID["space"]].get("bottom", ["fixed"])):
    raise _config_error(
        "identification.bottom", f"{ID['bottom']!r} is not a bottom of {ID['space']!r}"
    )
try:
    ID_ALPHAS = expand_axis(ID["figure7"]["alphas"])
    ID_LOOP_PRESSURES = expand_axis(ID["fe_in_the_loop"]["pressures_mbar"])
except ValueError as err:
    raise _config_error("identification", err)

for _axis in ("x1d", "x1h"):
    _values = [p[_axis] for p in grid_points(config["spaces"][ID["space"]])]
    if not min(_values) <= ID["target"][_axis] <= max(_values):
        raise _config_error(
            f"identification.target.{_axis}",
            f"{ID['target'][_axis]:g} MPa is outside the space {ID['space']!r} "
            f"({min(_values):g}..{max(_values):g} MPa)",
        )

ID_SPACE = f"results/simulated_space/{ID['space']}.parquet"
ID_TEST_POINTS = [
    point_id(
        {
            "probe_mm": probe,
            "bottom": ID["bottom"],
            "x1d": ID["target"]["x1d"],
            "x1h": ID["target"]["x1h"],
        }
    )
    for probe in (2.0, 6.0)
]
ID_CURVES = "results/identification/test_curves.csv"
ID_CODE = code_hash("paper", "identify", *SPACE_CODE, "measured")
ID_FIG_CODE = code_hash("paper", "identify", "figures", *SPACE_CODE, "measured")
#: the optimiser comparison also runs the classical optimisers of skinsuction.evaluation
ID_OPT_CODE = code_hash(
    "paper", "identify", "figures", "evaluation/_baselines.py", *SPACE_CODE, "measured"
)

IDENTIFICATION_OUTPUTS = [
    "results/figures/fig4_single_probe.png",
    "results/figures/fig4_single_probe.pdf",
    "results/tables/fig4_single_probe.csv",
    "results/figures/fig4b_cost_landscape.png",
    "results/figures/fig4b_cost_landscape.pdf",
    "results/tables/fig4b_cost_landscape.csv",
    "results/figures/fig7_alpha.png",
    "results/figures/fig7_alpha.pdf",
    "results/tables/fig7_alpha.csv",
    "results/tables/fig7_alpha_threshold.csv",
    "results/figures/fig8_ratio.png",
    "results/figures/fig8_ratio.pdf",
    "results/tables/fig8_ratio.csv",
    "results/tables/timing.csv",
    "results/tables/timing.md",
    "results/tables/optimiser_comparison.csv",
    "results/tables/optimiser_comparison.md",
]


rule simulate_test_curve:
    output:
        curve="results/identification/test_curves/{point}.parquet",
    log:
        "logs/identification/test_curves/{point}.log",
    benchmark:
        "results/benchmarks/identification/test_curve_{point}.tsv"
    params:
        # same pressures, mesh and fallback as the simulated space: only the point
        # is off the grid
        pressures=PRESSURES,
        mesh=config["mesh"],
        fallback=config["mesh_fallback"],
        code=code_hash(*FE_CODE),
    threads: 1
    resources:
        mem_mb=2000,
        runtime=30,
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/simulate_test_curve.py"


rule identification_test_curves:
    input:
        space=ID_SPACE,
        fe=expand("results/identification/test_curves/{point}.parquet", point=ID_TEST_POINTS),
    output:
        curves=ID_CURVES,
    log:
        "logs/identification/test_curves.log",
    params:
        target=ID["target"],
        bottom=ID["bottom"],
        code=ID_CODE,
    threads: 1
    resources:
        mem_mb=2000,
        runtime=10,
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/identification_test_curves.py"


rule identification_runs:
    input:
        space=ID_SPACE,
        curves=ID_CURVES,
    output:
        runs="results/identification/{study}_runs.csv",
    log:
        "logs/identification/{study}_runs.log",
    benchmark:
        "results/benchmarks/identification/{study}_runs.tsv"
    wildcard_constraints:
        study="single_probe|alpha_sweep|ratio",
    params:
        settings=ID,
        alphas=ID_ALPHAS,
        code=ID_CODE,
    threads: 1
    resources:
        mem_mb=2000,
        runtime=60,
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/identification_runs.py"


rule timing_table:
    input:
        space=ID_SPACE,
        curves=ID_CURVES,
    output:
        table=report(
            "results/tables/timing.csv",
            caption="../report/timing.rst",
            category="Tables",
            labels={"table": "timing", "format": "csv"},
        ),
        markdown=report(
            "results/tables/timing.md",
            caption="../report/timing.rst",
            category="Tables",
            labels={"table": "timing", "format": "md"},
        ),
        runs="results/identification/timing_runs.csv",
    log:
        "logs/identification/timing.log",
    benchmark:
        "results/benchmarks/identification/timing.tsv"
    params:
        settings=ID,
        code=ID_FIG_CODE,
    # two cores (capped at --cores): on the 2-core study machine the timed
    # identifications, single-threaded, run with no other job beside them
    threads: 2
    resources:
        mem_mb=2000,
        runtime=30,
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/timing_table.py"


rule fe_in_the_loop:
    input:
        space=ID_SPACE,
    output:
        result="results/identification/fe_in_the_loop.json",
    log:
        "logs/identification/fe_in_the_loop.log",
    benchmark:
        "results/benchmarks/identification/fe_in_the_loop.tsv"
    params:
        settings=ID,
        loop=ID["fe_in_the_loop"],
        pressures=ID_LOOP_PRESSURES,
        code=code_hash("paper", "identify", "model", *SPACE_CODE),
    threads: 1
    resources:
        mem_mb=2000,
        runtime=120,
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/fe_in_the_loop.py"


rule optimiser_comparison:
    input:
        space=ID_SPACE,
        curves=ID_CURVES,
        fe_loop="results/identification/fe_in_the_loop.json",
    output:
        table=report(
            "results/tables/optimiser_comparison.csv",
            caption="../report/optimisers.rst",
            category="Tables",
            labels={"table": "optimisers", "format": "csv"},
        ),
        markdown=report(
            "results/tables/optimiser_comparison.md",
            caption="../report/optimisers.rst",
            category="Tables",
            labels={"table": "optimisers", "format": "md"},
        ),
        runs="results/identification/optimiser_runs.csv",
    log:
        "logs/identification/optimiser_comparison.log",
    benchmark:
        "results/benchmarks/identification/optimiser_comparison.tsv"
    params:
        settings=ID,
        code=ID_OPT_CODE,
    threads: 1
    resources:
        mem_mb=2000,
        runtime=60,
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/optimiser_comparison.py"


if "scale_free_space" in config:

    IDENTIFICATION_OUTPUTS += [
        "results/tables/scale_free_vs_paper.csv",
        "results/tables/scale_free_vs_paper.md",
    ]

    rule scale_free_vs_paper:
        """The honest test curve identified on the paper grid and on the scale-free space."""
        input:
            paper=ID_SPACE,
            scale_free=SF_SPACES[0],  # the neo-Hookean model comes first
            curves=ID_CURVES,
        output:
            table=report(
                "results/tables/scale_free_vs_paper.csv",
                caption="../report/scale_free_vs_paper.rst",
                category="Identification",
                labels={"table": "paper grid vs scale-free space"},
            ),
            md="results/tables/scale_free_vs_paper.md",
            runs="results/identification/scale_free_vs_paper_runs.csv",
        log:
            "logs/identification/scale_free_vs_paper.log",
        benchmark:
            "results/benchmarks/identification/scale_free_vs_paper.tsv"
        params:
            settings={k: ID[k] for k in ("target", "bottom", "repeats", "seed", "alpha",
                                         "success_tolerance", "window_focusing")},
            code=code_hash("paper", "identify", "figures", *SPACE_CODE),
        threads: 1
        resources:
            mem_mb=2000,
            runtime=30,
        conda:
            "../envs/skinsuction.yaml"
        script:
            "../scripts/scale_free_vs_paper.py"
