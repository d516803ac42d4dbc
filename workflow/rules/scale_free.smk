"""The scale-free simulated space (what `skinsuction identify` and `diagnose` read).

Included by the Snakefile when the configuration has a `scale_free_space` section.

config.scale_free_space -> FE ray bundles, one job per (model, probe, X1h/X1d)
  (results/simulated_space/scale_free/rays/<bundle>.parquet)
  -> one space per model: neo_hookean + one per cause
  (results/simulated_space/scale_free/<model>.parquet)
  -> coverage frontier (results/tables/scale_free_coverage.csv, figure)

A ray is one FE curve at X1d = x1d_ref loaded to p/X1d = load.max; the scaling
law M(s X1d, s X1h, s X2d, s p) = M(X1d, X1h, X2d, p) makes it cover every X1d
(see skinsuction.space). The rays of a cause at its neutral value are
the neo-Hookean rays: the same jobs.
"""

from skinsuction.space import (  # noqa: E402
    BASELINE,
    BUNDLE_ID_PATTERN,
    RaySpec,
    bundle_id,
    ray_bundles,
    registry_from_config,
)

SF = config["scale_free_space"]
try:
    SF_CAUSES = registry_from_config(SF["causes"])
    SF_SPEC = RaySpec.from_config(SF, config.get("mesh"), config.get("mesh_fallback"))
except (KeyError, ValueError) as err:
    raise _config_error("scale_free_space", err)
SF_MODELS = {BASELINE: None, **SF_CAUSES}
SF_BUNDLES = ray_bundles(SF_SPEC, SF_CAUSES)
SF_DIR = "results/simulated_space/scale_free"
SF_SPACES = expand(f"{SF_DIR}/{{model}}.parquet", model=SF_MODELS)


# bundle files that hold the rays of each model: its own and the neutral (neo-Hookean) ones
SF_MODEL_BUNDLES = {
    model: [
        f"{SF_DIR}/rays/{b}.parquet"
        for b in SF_BUNDLES
        if b.startswith(f"{model}__") or b.startswith(f"{BASELINE}__")
    ]
    for model in SF_MODELS
}


wildcard_constraints:
    bundle=BUNDLE_ID_PATTERN,
    model="|".join(map(re.escape, SF_MODELS)),


SCALE_FREE_OUTPUTS = [
    *SF_SPACES,
    "results/tables/scale_free_coverage.csv",
    "results/figures/scale_free_coverage.png",
    "results/figures/scale_free_coverage.pdf",
]


localrules:
    scale_free_space,


rule scale_free_space:
    """Target: every model of the scale-free space and its coverage frontier."""
    input:
        SCALE_FREE_OUTPUTS,


rule simulate_ray_bundle:
    output:
        bundle=f"{SF_DIR}/rays/{{bundle}}.parquet",
    log:
        "logs/scale_free/rays/{bundle}.log",
    benchmark:
        "results/benchmarks/scale_free/rays/{bundle}.tsv"
    params:
        # a change of any of these reruns the FE jobs (Snakemake's params trigger)
        rays=lambda w: SF_BUNDLES[w.bundle],
        pressures=list(SF_SPEC.pressures_mbar),
        onset=list(SF_SPEC.onset_mbar),
        mesh=SF_SPEC.mesh,
        fallback=[dict(f) for f in SF_SPEC.fallback],
        # the model, the fallback chain, the curve format and the ray ids
        code=code_hash(*FE_RAY_CODE),
    threads: 1
    resources:
        mem_mb=2000,
        runtime=60,
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/simulate_ray_bundle.py"


rule assemble_scale_free_space:
    input:
        bundles=lambda w: SF_MODEL_BUNDLES[w.model],
    output:
        space=f"{SF_DIR}/{{model}}.parquet",
    log:
        "logs/scale_free/{model}.log",
    params:
        spec=SF_SPEC.to_dict(),
        cause=lambda w: SF["causes"].get(w.model),
        code=code_hash("diagnose", *SPACE_CODE),
    threads: 1
    resources:
        mem_mb=2000,
        runtime=10,
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/assemble_scale_free_space.py"
