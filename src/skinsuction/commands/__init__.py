"""The subcommands of ``skinsuction``, one module each.

Every module (``simulate``, ``export_inp``, ``identify``, ``diagnose``, ``study``, ``design``,
``rparams``, ``check_config``) has ``HELP`` and ``DESCRIPTION`` (its ``--help`` texts),
``add_arguments(parser)`` and ``run(args) -> int`` (the exit code); the registry
of :mod:`skinsuction.cli` names them.  What they share (exit codes, the
one-line :class:`CLIError`, formatting, and every
argument that more than one command takes) is in :mod:`._common`.

A command does its work through the public names of the lower layers
(``skinsuction.measured``, ``identify``, ``diagnose``, ``cohort``, ...) and only
takes the arguments, reads the input, prints and writes; its heavy imports
happen when it runs, so ``skinsuction --help`` stays quick.

Examples
--------
>>> import argparse
>>> from skinsuction.commands import simulate
>>> p = argparse.ArgumentParser()
>>> simulate.add_arguments(p)
>>> p.parse_args(["--probe", "6", "--x1d", "0.08", "--x1h", "4.1e-4"]).max_mbar
100.0
"""

from ._common import (
    EXIT_INPUT,
    EXIT_INTERNAL,
    EXIT_INTERRUPTED,
    EXIT_NOT_CONVERGED,
    EXIT_OK,
    CLIError,
)

__all__ = ["check_config", "design", "diagnose", "export_inp", "identify", "rparams", "simulate", "study", "CLIError",
           "EXIT_OK", "EXIT_INTERNAL", "EXIT_INPUT", "EXIT_NOT_CONVERGED", "EXIT_INTERRUPTED"]
