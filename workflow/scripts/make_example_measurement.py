"""Rule make_example_measurement: the synthetic example of data/ (seeded, fine mesh).

The file is shipped; this rule only runs where it is missing.  The same
function remakes it by hand:  python -m skinsuction.diagnose.example OUT.csv
"""

from skinsuction.provenance import log_to_file

with log_to_file(snakemake.log[0]):
    from skinsuction.diagnose.example import make_example

    make_example(snakemake.output.csv)
