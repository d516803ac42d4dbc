"""Rule ship_pair_spaces (developer): copy the built pair spaces into the package, with PROVENANCE.json."""

from pathlib import Path

from skinsuction.jobs import job

with job(snakemake.log[0]):
    from skinsuction.space import ship_pair_spaces

    record = ship_pair_spaces(Path(snakemake.input.pairs[0]).parent.parent, snakemake.params.dest,
                              build_command=snakemake.params.build_command,
                              repo=snakemake.params.repo)
    for name, rec in record["files"].items():
        print(f"{name}: {rec['new_rays']} new rays, {rec['bytes']} bytes, "
              f"sha256 {rec['sha256'][:12]}")
