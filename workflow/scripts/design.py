"""Rule design: `skinsuction design` over the config's box, designs and question."""

import logging
from pathlib import Path

from skinsuction.jobs import job

with job(snakemake.log[0], threads=snakemake.threads):
    import sys

    from skinsuction.design import Box, Question, designs_from, run_design

    s = snakemake.params.settings
    skins = Box.from_config(s.get("box")).draw(s.get("skins", 40), s.get("seed", 0))
    designs = designs_from(s["probes"], s["suction_mbar"], noise_um=s.get("noise_um", 2.0),
                           resolution_mm=s.get("resolution_mm", 0.01),
                           given=s.get("given", {}),
                           protocols=s.get("protocols", ["ramp"]),
                           timing=s.get("timing"), sample_hz=s.get("sample_hz", 100.0))
    q = s.get("question", {})
    question = Question(dict(q.get("precision", {})), tuple(q.get("tell", ())),
                        q.get("quantile", 0.9), q.get("rate", 0.95))
    r = run_design(skins, designs, question, Path(snakemake.output.markdown).parent,
                   space_dir=snakemake.params.space_dir, workers=snakemake.threads,
                   source=f"{len(skins)} drawn from the box of the config, seed "
                          f"{s.get('seed', 0)}", seed=s.get("seed", 0), progress=sys.stderr)
    logging.getLogger("skinsuction.design").info(
        "%s: %s (%.1f s)", question.text,
        ("recommended " if r["recommendation"]["met"] else "none meets it; best ")
        + r["recommendation"]["design"], r["seconds"])
