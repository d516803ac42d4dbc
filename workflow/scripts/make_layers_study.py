"""Rule make_layers_study: the SYNTHETIC subjects with their own layers (FE virtual experiments)."""

from skinsuction.jobs import job

# one process per thread, each with single-threaded BLAS/OpenMP pools
with job(snakemake.log[0], threads=1):
    import sys

    from skinsuction.evaluation import LayersStudyDesign, make_layers_study

    design = LayersStudyDesign.from_config(snakemake.params.design)
    truth = make_layers_study(snakemake.output.folder, snakemake.output.truth, design,
                              processes=snakemake.threads, progress=sys.stderr)
    print(f"{truth['subject'].nunique()} subjects, {len(truth)} files; "
          f"{(truth['redrawn_because'].fillna('') != '').sum() // 2} subjects redrawn")
