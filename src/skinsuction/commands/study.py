"""``skinsuction study``: identify and diagnose every measurement of a clinical study.

::

    skinsuction study FOLDER_OR_LONG.csv --out DIR [--no-diagnose] [--workers 2]

The work is :func:`skinsuction.cohort.run_study`; this module only takes the
arguments and prints the summary.
"""

from __future__ import annotations

import argparse

from skinsuction._argtypes import positive_int

from ._common import EXIT_OK, CLIError, add_level, add_out, add_repeats, add_seed, add_space

__all__ = ["HELP", "DESCRIPTION", "add_arguments", "run"]

HELP = "identify and diagnose every curve of a clinical study, compare the groups"

DESCRIPTION = (
    "Identify (X1d, X1h with 95 % profile-likelihood intervals) and diagnose every "
    "measurement of a study: a folder of measured CSVs or one long CSV with id "
    "columns (subject, site, visit, group, ...). A bad file becomes a row with its "
    "error. Writes DIR/curves.parquet (one row per measurement), DIR/comparison.csv "
    "and DIR/summary.md (paired Wilcoxon within groups, Mann-Whitney between "
    "groups), DIR/study.json and figures.")


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Every argument of ``skinsuction study``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser.

    Returns
    -------
    None
    """
    p.add_argument("path", metavar="PATH",
                   help="a folder of measured CSVs (ids from '# key: value' lines and an "
                        "optional manifest.csv/.yaml) or one long CSV whose extra columns "
                        "(subject, site, visit, group, ...) are ids")
    add_out(p, help="output folder: curves.parquet, comparison.csv, summary.md, "
                    "study.json and figures")
    add_space(p, help="the scale-free simulated space. Default: "
                      "results/simulated_space/scale_free if the workflow has built it "
                      "under the working directory, else the default space shipped with "
                      "skinsuction; the space used is printed and recorded in study.json "
                      "and summary.md")
    p.add_argument("--no-diagnose", action="store_true",
                   help="identify only (much faster: no diagnosis of each curve)")
    add_repeats(p, default=2,
                help="window focusing runs per identification, polished (default 2)")
    add_seed(p, help="seed of the study; measurement i uses seed + i (default 0)")
    add_level(p, default=0.95, help="confidence level of the intervals (default 0.95)")
    p.add_argument("--workers", type=positive_int, default=1,
                   help="processes (default 1)")
    p.add_argument("--reports", action="store_true",
                   help="also write each measurement's identification and diagnosis files "
                        "(off by default: thousands of folders for big studies)")
    p.add_argument("--restart", action="store_true",
                   help="analyse every measurement afresh. By default a rerun into the same "
                        "--out with the same files, space and settings takes the rows a run "
                        "cut short had finished (kept in DIR/rows.partial.jsonl)")


def run(args: argparse.Namespace) -> int:
    """Run ``skinsuction study``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments of :func:`add_arguments`.

    Returns
    -------
    int
        0 (a bad measurement is a row with its error; a missing study raises).
    """
    from skinsuction.cohort import run_study

    try:
        r = run_study(args.path, args.out, space_dir=args.space, diagnose=not args.no_diagnose,
                      repeats=args.repeats, seed=args.seed, level=args.level,
                      workers=args.workers, reports=args.reports, resume=not args.restart)
    except FileNotFoundError as err:
        raise CLIError(str(err)) from None
    print(f"space: {r['space']}")
    print(f"{r['measurements']} measurements, {r['errors']} with an error, "
          f"{r['seconds']:.1f} s"
          + (f" ({r['resumed']} taken from the run cut short)" if r["resumed"] else ""))
    for c in r["comparison"]:
        if c.get("p_value") is None:
            continue
        print(f"{c['group']} ({c.get('comparison', '')}): median change "
              f"{c['median_change_percent']:+.1f} % "
              + (f"[{c['ci_low_percent']:+.1f}, {c['ci_high_percent']:+.1f}] "
                 if c.get("ci_low_percent") is not None else "")
              + f"p = {c['p_value']:.2g}, {c['test']}")
    print(f"wrote {', '.join(r['paths'].values())}")
    return EXIT_OK
