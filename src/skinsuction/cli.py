"""The ``skinsuction`` command: ``simulate`` a suction test, ``identify`` moduli,
``diagnose`` the misfit of the neo-Hookean model, run a whole ``study``.

::

    skinsuction simulate --probe 6 --x1d 0.08 --x1h 4.1e-4 [--out curve.csv]
    skinsuction identify MEASURED.csv [--space PATH] \\
        --objective single|weighted|ratio [--probe 6] [--alpha 0.5] [--repeats 100] \\
        [--seed 0] --out DIR
    skinsuction diagnose MEASURED.csv --out DIR
    skinsuction study FOLDER_OR_LONG.csv --out DIR [--no-diagnose] [--workers 2]
    skinsuction design --out DIR [--probes 2 2+6 4+8] [--suction 100 500] [--precision X1h=0.2]
    skinsuction rparams TIME_CURVES.csv --out DIR [--ue-time-s 0.1]
    skinsuction check-config CONFIG.yaml

This module holds the parser (:func:`build_parser`), :func:`main` and the registry
of commands (:data:`COMMANDS`).  Each subcommand is a module of
:mod:`skinsuction.commands` (its help, a function that adds its arguments to an
``argparse`` parser and a function that runs it and returns the exit code),
named here by a :class:`Command`.  A new subcommand is one more module and one
more entry.

Exit codes: 0 success; 1 unexpected internal error (one line; ``--debug`` shows
the traceback); 2 bad usage or bad input (one line naming the file, line and
column where it applies, never a traceback); 3 ``simulate`` stopped before the
last pressure (the partial curve is still written); 130 interrupted.

Examples
--------
>>> main(["--version"])  # doctest: +ELLIPSIS
skinsuction ...
0
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass
from typing import Callable

from skinsuction.commands import (
    EXIT_INPUT,
    EXIT_INTERNAL,
    EXIT_INTERRUPTED,
    EXIT_NOT_CONVERGED,
    EXIT_OK,
    CLIError,
    check_config,
    design,
    diagnose,
    export_inp,
    identify,
    rparams,
    simulate,
    study,
)

__all__ = ["main", "build_parser", "COMMANDS", "Command", "CLIError", "EXIT_OK",
           "EXIT_INTERNAL", "EXIT_INPUT", "EXIT_NOT_CONVERGED", "EXIT_INTERRUPTED"]


@dataclass(frozen=True)
class Command:
    """A subcommand: its name, its help, how it adds its arguments, how it runs.

    Parameters
    ----------
    name : str
        The word after ``skinsuction``.
    help : str
        One line for ``skinsuction --help``.
    description : str
        The paragraph of ``skinsuction NAME --help``.
    add_arguments : callable
        ``add_arguments(parser)`` adds the subcommand's arguments.
    run : callable
        ``run(args) -> int`` runs it and returns the exit code.
    """

    name: str
    help: str
    description: str
    add_arguments: Callable[[argparse.ArgumentParser], None]
    run: Callable[[argparse.Namespace], int]

    @classmethod
    def of(cls, name: str, module) -> "Command":
        """The command of a module of :mod:`skinsuction.commands`.

        Parameters
        ----------
        name : str
            The word after ``skinsuction``.
        module : module
            With ``HELP``, ``DESCRIPTION``, ``add_arguments`` and ``run``.

        Returns
        -------
        Command
        """
        return cls(name, module.HELP, module.DESCRIPTION, module.add_arguments, module.run)


#: The subcommands, in the order of ``skinsuction --help``.
COMMANDS = {
    c.name: c
    for c in (
        Command.of("simulate", simulate),
        Command.of("identify", identify),
        Command.of("diagnose", diagnose),
        Command.of("study", study),
        Command.of("design", design),
        Command.of("rparams", rparams),
        Command.of("check-config", check_config),
        Command.of("export-inp", export_inp),
    )
}


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand of :data:`COMMANDS`.

    Returns
    -------
    argparse.ArgumentParser
        Parsed arguments carry ``run``, the subcommand's run function.
    """
    from skinsuction import __version__

    parser = argparse.ArgumentParser(
        prog="skinsuction",
        description="Elastic moduli of two skin layers (dermis, hypodermis) from suction "
                    "tests by inverse finite-element analysis.",
    )
    parser.add_argument("--version", action="version", version=f"skinsuction {__version__}")
    parser.add_argument("--debug", action="store_true",
                        help="show the Python traceback of unexpected errors")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for c in COMMANDS.values():
        p = sub.add_parser(c.name, help=c.help, description=c.description)
        c.add_arguments(p)
        p.set_defaults(run=c.run)
    return parser


def main(argv=None) -> int:
    """Run the command line.

    Parameters
    ----------
    argv : list of str, optional
        The arguments after ``skinsuction`` (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        The exit code (see the module docstring).
    """
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exit_:  # --help, --version, usage errors
        return int(exit_.code or 0)
    from skinsuction._memory import keep_freed_memory
    from skinsuction.errors import InputError
    from skinsuction.measured import MeasuredDataError

    keep_freed_memory()  # the fits' large arrays reused, not re-faulted (docs/workflow.md)
    try:
        return args.run(args)
    except CLIError as err:
        code, message = err.code, str(err)
    except (MeasuredDataError, InputError) as err:
        code, message = EXIT_INPUT, str(err)
    except KeyboardInterrupt:
        print(f"skinsuction {args.command}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:  # e.g. `skinsuction simulate ... | head`
        sys.stderr.close()
        return EXIT_OK
    except Exception as err:  # noqa: BLE001 - one line unless --debug
        if args.debug:
            raise
        code = EXIT_INTERNAL
        message = (f"internal error: {type(err).__name__}: {err} "
                   "(run with --debug for the traceback)")
    print(f"skinsuction {args.command}: error: {' '.join(message.split())}", file=sys.stderr)
    return code


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
