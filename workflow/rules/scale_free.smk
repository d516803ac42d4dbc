"""The scale-free simulated space (what `skinsuction identify` and `diagnose` read).

Included by the Snakefile when the configuration has a `scale_free_space` section.

config.scale_free_space -> FE ray bundles, one job per (model, probe, X1h/X1d)
  (results/simulated_space/scale_free/rays/<bundle>.parquet)
  -> one space per model: neo_hookean + one per cause
  (results/simulated_space/scale_free/<model>.parquet)
  -> coverage frontier (results/tables/scale_free_coverage.csv, figure)
  -> check against the default space shipped with the package, ray by ray
  (results/tables/shipped_space_check.csv; default target)

config.scale_free_space.pairs -> the rays of two causes at once, both away from
  neutral (their edges are the single causes' spaces)
  -> results/simulated_space/scale_free/pairs/<pair>.parquet (target
  scale_free_pairs; not in the default target: about 3 100 FE rays, some 45 CPU-min,
  so the study reads the pairs shipped with the package unless they are built)

config.scale_free_space.geometry -> the neo-Hookean rays over the subject's
  geometry (t_d/a x t_h/a x X1h/X1d), and those of the causes in its `causes`
  (on their own grid), one job per model and t_d/a node
  -> results/simulated_space/scale_free/geometry/<model>.parquet (target
  scale_free_geometry; not in the default target: 5 824 neo-Hookean FE rays, some 2.7
  CPU-h, and the causes' more, so identify, diagnose and study read the ones shipped
  with the package unless built)

Developer rule, not in any target: `snakemake --cores 2 ship_scale_free_space`
copies the built model files into src/skinsuction/data/scale_free/ with
PROVENANCE.json (what identify, diagnose and study read when no build is in the
working directory).

A ray is one FE curve at X1d = x1d_ref loaded to p/X1d = load.max; the scaling
law M(s X1d, s X1h, s X2d, s p) = M(X1d, X1h, X2d, p) makes it cover every X1d
(see skinsuction.space). The rays of a cause at its neutral value are
the neo-Hookean rays: the same jobs.
"""

from skinsuction.space import (  # noqa: E402
    BASELINE,
    BUNDLE_ID_PATTERN,
    SHIPPED_ATOL_MM,
    SHIPPED_RTOL,
    PAIRS_FOLDER,
    RaySpec,
    bundle_id,
    pair_bundles,
    pairs_from_config,
    ray_bundles,
    registry_from_config,
    sample_bundles,
    shipped_check_applies,
    shipped_provenance,
    GEOMETRY_FOLDER,
    GeometryGrid,
)

SF = config["scale_free_space"]
try:
    SF_CAUSES = registry_from_config(SF["causes"])
    SF_SPEC = RaySpec.from_config(SF, config.get("mesh"), config.get("mesh_fallback"))
    SF_PAIRS = pairs_from_config(SF.get("pairs"), SF_CAUSES)
except (KeyError, ValueError) as err:
    raise _config_error("scale_free_space", err)
SF_MODELS = {BASELINE: None, **SF_CAUSES}
# the geometry spaces' rays stop where the load tail starts (their build is 2.7 + 3.3
# CPU-h without it); the rays on demand, which they serve, do the same
SF_GEOMETRY_SPEC = SF_SPEC.untailed()
SF_PAIR_BUNDLES = pair_bundles(SF_SPEC, SF_PAIRS, SF.get("rays_per_job", 1))
SF_BUNDLES = {**ray_bundles(SF_SPEC, SF_CAUSES, SF.get("rays_per_job", 1)), **SF_PAIR_BUNDLES}
SF_DIR = "results/simulated_space/scale_free"
# the space built here (target scale_free_space, whatever the source)
SF_BUILT_SPACES = expand(f"{SF_DIR}/{{model}}.parquet", model=SF_MODELS)
SF_SOURCE = SF.get("source", "build")
if SF_SOURCE == "shipped":
    # the study reads the shipped space (no 70 CPU-min of FE rays), if it was built from
    # this very configuration; a sample of its rays is solved afresh and compared
    _applies, _why = shipped_check_applies(
        SF_SPEC, SF_CAUSES, shipped_provenance(SF_SHIPPED) if SF_SHIPPED.is_dir() else None
    )
    if not _applies:
        raise _config_error("scale_free_space.source", f"shipped, but {_why}; set it to build")
    SF_SPACES = [str(SF_SHIPPED / f"{m}.parquet") for m in SF_MODELS]
else:
    SF_SPACES = SF_BUILT_SPACES

# model -> (its cause or None, its grid) of the geometry spaces: the neo-Hookean one and
# those of the causes named in scale_free_space.geometry.causes (their own, coarser grid)
SF_GEOMETRY = {}
if SF.get("geometry"):
    try:
        SF_GEOMETRY[BASELINE] = (None, GeometryGrid.from_config(SF["geometry"]))
        _gc = SF["geometry"].get("causes") or {}
        for _name in _gc.get("names", []):
            if _name not in SF_CAUSES or SF_CAUSES[_name].geometric:
                raise ValueError(f"causes.names: {_name!r} is not a cause of the space other "
                                 "than a thickness (those are neo-Hookean rays)")
            _own = {axis: (_gc.get(f"{axis}_of") or {}).get(_name)
                    for axis in ("t_d_over_a", "t_h_over_a")}
            SF_GEOMETRY[_name] = (SF_CAUSES[_name], GeometryGrid.from_config(
                {**_gc, **{k: v for k, v in _own.items() if v}}))
        for _key in ("t_d_over_a_of", "t_h_over_a_of"):
            for _name in _gc.get(_key) or {}:
                if _name not in _gc.get("names", []):
                    raise ValueError(f"causes.{_key}: {_name!r} is not in causes.names")
    except ValueError as err:
        raise _config_error("scale_free_space.geometry", err)
SF_GEOMETRY_DIR = f"{SF_DIR}/{GEOMETRY_FOLDER}"
# one job per model and t_d/a node: "td0.125" (neo-Hookean), "strain_stiffening__td0.125";
# a cause with t_h_per_job: one per t_d/a node and that many t_h/a nodes,
# "pre_tension__td0.125__th0.125" (jobs of minutes: a cut run or a cluster loses less)
SF_GEOMETRY_BUNDLES = {}
for _m, (_cause, _grid) in SF_GEOMETRY.items():
    _k = ((SF.get("geometry") or {}).get("causes") or {}).get("t_h_per_job", {}).get(_m)
    _k = _k or len(_grid.th_nodes)
    for _td in _grid.td_nodes:
        for _j in range(0, len(_grid.th_nodes), _k):
            _ths = _grid.th_nodes[_j : _j + _k]
            _name = (f"{_m}__" if _m != BASELINE else "") + f"td{_td:g}"
            _name += "" if _k >= len(_grid.th_nodes) else f"__th{_ths[0]:g}"
            SF_GEOMETRY_BUNDLES[_name] = (_m, _td, _cause, _grid, _ths)
SF_GEOMETRY_SPACES = {m: f"{SF_GEOMETRY_DIR}/{m}.parquet" for m in SF_GEOMETRY}
SF_GEOMETRY_SPACE = [SF_GEOMETRY_SPACES[BASELINE]] if SF_GEOMETRY else []


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
    gbundle="|".join(map(re.escape, SF_GEOMETRY_BUNDLES)) or "no_geometry",
    gmodel="|".join(map(re.escape, SF_GEOMETRY)) or "no_geometry",
    model="|".join(map(re.escape, SF_MODELS)),
    pair="|".join(map(re.escape, SF_PAIRS)) or "no_pair",


SCALE_FREE_OUTPUTS = [
    *SF_SPACES,
    "results/tables/scale_free_coverage.csv",
    "results/figures/scale_free_coverage.png",
    "results/figures/scale_free_coverage.pdf",
]

#: in the default target (Snakefile): a build is checked ray by ray against the shipped
#: space (the check says itself whether it applies); the shipped space read instead is
#: checked against a sample of its rays solved afresh
SHIPPED_CHECK_OUTPUTS = [
    "results/tables/shipped_space_check.csv"
    if SF_SOURCE == "build"
    else "results/tables/shipped_space_sample_check.csv"
]
SF_CHECK_BUNDLES = sample_bundles(
    [b for b in SF_BUNDLES if b not in SF_PAIR_BUNDLES],
    SF.get("check_bundles", 4),
    SF.get("check_seed", 0),
)


SF_PAIR_SPACES = expand(f"{SF_DIR}/{PAIRS_FOLDER}/{{pair}}.parquet", pair=SF_PAIRS)


localrules:
    scale_free_space,
    scale_free_pairs,
    scale_free_geometry,
    ship_geometry_space,
    ship_scale_free_space,
    ship_pair_spaces,


rule scale_free_space:
    """Target: every model of the scale-free space built here from FE rays, checked ray
    by ray against the shipped one, and the coverage frontier of the space the study
    reads."""
    input:
        SCALE_FREE_OUTPUTS,
        SF_BUILT_SPACES,
        "results/tables/shipped_space_check.csv",


rule scale_free_pairs:
    """Target: the spaces of the pairs of causes (scale_free_space.pairs)."""
    input:
        SF_PAIR_SPACES,


rule scale_free_geometry:
    """Target: the spaces over the subject's geometry (scale_free_space.geometry): the
    neo-Hookean one and the causes' (the file of one model is a target of its own)."""
    input:
        list(SF_GEOMETRY_SPACES.values()),


rule simulate_geometry_bundle:
    """The FE rays of one model at one t_d/a node of its geometry space (every t_h/a,
    cause node and X1h/X1d)."""
    output:
        bundle=f"{SF_GEOMETRY_DIR}/rays/{{gbundle}}.parquet",
    log:
        "logs/scale_free/geometry/{gbundle}.log",
    benchmark:
        "results/benchmarks/scale_free/geometry/{gbundle}.tsv"
    params:
        bundle=lambda w: f"geometry__{w.gbundle}",
        rays=lambda w: (lambda m, td, cause, grid, ths: grid.ray_ids(SF_GEOMETRY_SPEC, td, cause, ths))(
            *SF_GEOMETRY_BUNDLES[w.gbundle]
        ),
        pressures=list(SF_GEOMETRY_SPEC.pressures_mbar),
        mesh=SF_GEOMETRY_SPEC.mesh,
        fallback=[dict(f) for f in SF_GEOMETRY_SPEC.fallback],
        code=code_hash(*FE_RAY_CODE),
    threads: 1
    resources:
        mem_mb=2000,
        runtime=60,
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/simulate_ray_bundle.py"


rule assemble_geometry_space:
    input:
        bundles=lambda w: [f"{SF_GEOMETRY_DIR}/rays/{b}.parquet"
                           for b, (m, *_) in SF_GEOMETRY_BUNDLES.items() if m == w.gmodel],
    output:
        space=f"{SF_GEOMETRY_DIR}/{{gmodel}}.parquet",
    log:
        "logs/scale_free/geometry/assemble_{gmodel}.log",
    params:
        spec=SF_GEOMETRY_SPEC.to_dict(),
        grid=lambda w: SF_GEOMETRY[w.gmodel][1].to_dict(),
        cause=lambda w: None if w.gmodel == BASELINE else w.gmodel,
        causes=SF.get("causes"),
        code=code_hash(*SPACE_CODE),
    threads: 1
    resources:
        mem_mb=2000,
        runtime=10,
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/assemble_geometry_space.py"


rule ship_geometry_space:
    """Developer rule (no target asks for it): ship the built geometry spaces with the package.

    Copies results/simulated_space/scale_free/geometry/<model>.parquet into
    src/skinsuction/data/scale_free/geometry/, recorded in its own PROVENANCE.json.
    """
    input:
        space=list(SF_GEOMETRY_SPACES.values()),
    log:
        "logs/scale_free/ship_geometry_space.log",
    params:
        dest=str(SF_SHIPPED),
        repo=str(Path(workflow.basedir)),
        build_command="snakemake --cores 2 scale_free_geometry",
    threads: 1
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/ship_geometry_space.py"


rule ship_geometry_model:
    """Developer rule: ship one model's built geometry space (``ship_geometry_space`` ships
    them all): ``snakemake --cores 1 logs/scale_free/geometry/ship_<model>.json``."""
    input:
        space=f"{SF_GEOMETRY_DIR}/{{gmodel}}.parquet",
    output:
        manifest="logs/scale_free/geometry/ship_{gmodel}.json",
    log:
        "logs/scale_free/geometry/ship_{gmodel}.log",
    params:
        dest=str(SF_SHIPPED),
        repo=str(Path(workflow.basedir)),
        build_command=lambda w: f"snakemake --cores 2 {SF_GEOMETRY_DIR}/{w.gmodel}.parquet",
    threads: 1
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/ship_geometry_space.py"


rule unpack_geometry_space:
    """Developer rule (no target asks for it): the shipped geometry space of a model back
    in job files, so that a grid with more nodes solves only the new ones.

    ``snakemake --cores 2 logs/scale_free/geometry/unpack_<model>.json``, then build the
    space with ``--rerun-triggers mtime`` (the job files have no Snakemake record).
    """
    input:
        space=lambda w: str(SF_SHIPPED / GEOMETRY_FOLDER / f"{w.gmodel}.parquet"),
    output:
        manifest="logs/scale_free/geometry/unpack_{gmodel}.json",
    log:
        "logs/scale_free/geometry/unpack_{gmodel}.log",
    params:
        jobs=lambda w: {b: (td, list(ths)) for b, (m, td, _, _, ths) in SF_GEOMETRY_BUNDLES.items()
                        if m == w.gmodel},
        out_dir=f"{SF_GEOMETRY_DIR}/rays",
        cause=lambda w: None if w.gmodel == BASELINE else w.gmodel,
        causes=SF.get("causes"),
        code=code_hash(*FE_RAY_CODE),
    threads: 1
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/unpack_geometry_space.py"


rule assemble_pair_space:
    input:
        bundles=lambda w: [f"{SF_DIR}/rays/{b}.parquet" for b in SF_PAIR_BUNDLES
                           if b.startswith(f"{w.pair}__")],
        # the pair's edges: each cause's own space
        singles=lambda w: [f"{SF_DIR}/{c}.parquet" for c in SF_PAIRS[w.pair].cause_names],
    output:
        space=f"{SF_DIR}/{PAIRS_FOLDER}/{{pair}}.parquet",
    log:
        "logs/scale_free/pairs/{pair}.log",
    params:
        spec=SF_SPEC.to_dict(),
        pair=lambda w: SF_PAIRS[w.pair].to_dict(),
        code=code_hash("diagnose", *SPACE_CODE),
    threads: 1
    resources:
        mem_mb=2000,
        runtime=10,
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/assemble_pair_space.py"


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
        mesh=SF_SPEC.mesh,
        fallback=[dict(f) for f in SF_SPEC.fallback],
        fallback_below=SF_SPEC.fallback_below_mbar,
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


rule check_shipped_sample:
    """The shipped space, which the study reads (scale_free_space.source: shipped),
    against a sample of its ray bundles solved afresh with the current FE code. Fails,
    naming the rays, if any differs beyond the tolerance or in its NaN pattern."""
    input:
        bundles=expand(f"{SF_DIR}/rays/{{bundle}}.parquet", bundle=SF_CHECK_BUNDLES),
        shipped=shipped_space_files,
    output:
        table="results/tables/shipped_space_sample_check.csv",
    log:
        "logs/scale_free/check_shipped_sample.log",
    params:
        spec=SF_SPEC.to_dict(),
        causes=SF["causes"],
        shipped_dir=str(SF_SHIPPED),
        rtol=SHIPPED_RTOL,
        atol=SHIPPED_ATOL_MM,
        code=code_hash("space/_shipped.py", "space/_rays.py", "space/_causes.py",
                       "space/_shipped_check.py"),
    threads: 1
    resources:
        mem_mb=2000,
        runtime=10,
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/check_shipped_sample.py"


rule check_shipped_space:
    """The fresh build against the default space shipped with the package, ray by ray.

    Applies when the configuration's scale-free space is the one the shipped space
    was built from (its ray specification and causes, recorded in PROVENANCE.json);
    otherwise the table says why it does not apply. Fails, naming the rays, if any
    ray differs beyond the tolerance (relative 1e-9 + 1e-12 mm) or in its NaN pattern.
    """
    input:
        spaces=SF_BUILT_SPACES,
        shipped=shipped_space_files,
    output:
        table="results/tables/shipped_space_check.csv",
    log:
        "logs/scale_free/check_shipped_space.log",
    params:
        spec=SF_SPEC.to_dict(),
        causes=SF["causes"],
        shipped_dir=str(SF_SHIPPED),
        rtol=SHIPPED_RTOL,
        atol=SHIPPED_ATOL_MM,
        code=code_hash("space/_shipped.py", "space/_rays.py", "space/_causes.py"),
    threads: 1
    resources:
        mem_mb=2000,
        runtime=10,
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/check_shipped_space.py"


rule ship_scale_free_space:
    """Developer rule (no target asks for it): ship the built space with the package.

    Copies results/simulated_space/scale_free/<model>.parquet (not the ray bundles)
    into src/skinsuction/data/scale_free/ and writes PROVENANCE.json there. It has no
    output file, so it runs whenever it is asked for, and no rule depends on it.
    """
    input:
        spaces=SF_BUILT_SPACES,
    log:
        "logs/scale_free/ship_scale_free_space.log",
    params:
        dest=str(SF_SHIPPED),
        repo=str(Path(workflow.basedir)),
        config_file=lambda w: config_file_of_space(),
        build_command=lambda w: build_command(config_file_of_space()),
        ship_command=" ".join(["snakemake", *sys.argv[1:]]),
    threads: 1
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/ship_scale_free_space.py"


rule ship_pair_spaces:
    """Developer rule (no target asks for it): ship the built pair spaces with the package.

    Copies results/simulated_space/scale_free/pairs/<pair>.parquet into
    src/skinsuction/data/scale_free/pairs/ with its own PROVENANCE.json; the single
    spaces shipped there must have the same ray specification.
    """
    input:
        pairs=SF_PAIR_SPACES,
    log:
        "logs/scale_free/ship_pair_spaces.log",
    params:
        dest=str(SF_SHIPPED),
        repo=str(Path(workflow.basedir)),
        build_command="snakemake --cores 2 scale_free_pairs",
    threads: 1
    conda:
        "../envs/skinsuction.yaml"
    script:
        "../scripts/ship_pair_spaces.py"
