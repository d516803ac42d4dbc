"""``skinsuction check-config``: check a workflow configuration before snakemake reads it.

::

    skinsuction check-config CONFIG.yaml [MORE.yaml ...] [--base CONFIG.yaml | --no-base]
"""

from __future__ import annotations

import argparse

from ._common import EXIT_INPUT, EXIT_OK, CLIError

__all__ = ["HELP", "DESCRIPTION", "add_arguments", "run"]

HELP = "check a workflow configuration file before snakemake reads it"

DESCRIPTION = (
    "Read configuration file(s) as `snakemake --configfile` would, merged over the "
    "default config/config.yaml (or alone with --no-base), and check them against "
    "the workflow's schema. A YAML syntax error names the file, line and column "
    "(Snakemake's own message names neither); a bad value names its key. Exit code "
    "0 if valid, 2 otherwise. The workflow's further checks (a target outside its "
    "space, a figure naming an unknown space) run when snakemake starts.")


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Every argument of ``skinsuction check-config``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser.

    Returns
    -------
    None
    """
    p.add_argument("configfiles", nargs="+", metavar="CONFIG.yaml",
                   help="configuration file(s) as given to snakemake --configfile, in order")
    p.add_argument("--base", default=None, metavar="CONFIG.yaml",
                   help="the workflow's default configuration the files are merged over, as "
                        "Snakemake merges them (default: config/config.yaml if present)")
    p.add_argument("--no-base", action="store_true",
                   help="check the files alone (snakemake --replace-workflow-config)")
    p.add_argument("--schema", default=None, metavar="SCHEMA.yaml",
                   help="JSON schema (YAML) of the workflow "
                        "(default: workflow/schemas/config.schema.yaml)")


def run(args: argparse.Namespace) -> int:
    """Run ``skinsuction check-config``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments of :func:`add_arguments`.

    Returns
    -------
    int
        0 if the configuration is valid (an invalid one raises, exit code 2).
    """
    from pathlib import Path

    from skinsuction.config import (
        DEFAULT_CONFIG,
        DEFAULT_SCHEMA,
        check_config,
        merge,
        read_config,
    )

    schema = Path(args.schema) if args.schema else DEFAULT_SCHEMA
    if not schema.is_file():
        raise CLIError(f"{schema}: schema not found (run from the project's root, or give --schema)",
                       EXIT_INPUT)
    base = None if args.no_base else (Path(args.base) if args.base else
                                      (DEFAULT_CONFIG if DEFAULT_CONFIG.is_file() else None))
    given = {}
    for path in args.configfiles:
        given = merge(given, read_config(path))
    if given.get("whole_config", False):
        base = None  # as the workflow: such a file is not merged over the default
    config = merge(read_config(base), given) if base is not None else given
    names = ", ".join(args.configfiles)
    check_config(config, schema, source=names if base is None else f"{names} over {base}")
    print(f"{names}: valid YAML and a valid configuration"
          + (f" (merged over {base})" if base is not None else ""))
    return EXIT_OK
