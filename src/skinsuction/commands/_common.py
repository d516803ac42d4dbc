"""What the commands share: exit codes, the user-facing error, formatting, arguments.

An argument that more than one command takes is defined here once (its flag,
type, metavar and destination); each command passes the help sentence that says
what the argument means for it.

Examples
--------
>>> import argparse
>>> p = argparse.ArgumentParser()
>>> add_seed(p, help="random seed")
>>> add_level(p, default=0.95, help="confidence level")
>>> p.parse_args(["--seed", "3"])
Namespace(seed=3, level=0.95)
>>> fmt(0.1 + 0.2), fmt(float("nan"))
('0.3', 'nan')
"""

from __future__ import annotations

import argparse
import math
from contextlib import contextmanager

from skinsuction._argtypes import non_negative_int, open_unit_interval, positive, positive_int

__all__ = [
    "EXIT_OK", "EXIT_INTERNAL", "EXIT_INPUT", "EXIT_NOT_CONVERGED", "EXIT_INTERRUPTED",
    "CLIError", "writing", "interval_text", "fmt", "BOTTOMS",
    "add_measured", "add_out", "add_space", "add_probe", "add_bottom", "add_seed",
    "add_repeats", "add_level", "add_noise_um", "add_geometry_arguments",
    "thickness_from_args", "THICKNESS_KEYS",
]

#: Exit codes: success; unexpected internal error; bad usage or input; ``simulate``
#: stopped before the last pressure; interrupted.
EXIT_OK, EXIT_INTERNAL, EXIT_INPUT, EXIT_NOT_CONVERGED, EXIT_INTERRUPTED = 0, 1, 2, 3, 130

#: Bottom conditions of the hypodermis over the bone.
BOTTOMS = ("fixed", "axial", "free")

#: The layer-thickness options, as keywords of :func:`skinsuction.measured.geometry_of`.
THICKNESS_KEYS = ("dermis_thickness_mm", "dermis_thickness_sd_mm", "hypodermis_thickness_mm",
                  "hypodermis_thickness_sd_mm")


class CLIError(Exception):
    """A user-facing error: printed as one line, exits with ``code``.

    Parameters
    ----------
    message : str
        What went wrong; any line breaks are folded into one line.
    code : int
        The exit code (default :data:`EXIT_INPUT`).
    """

    def __init__(self, message: str, code: int = EXIT_INPUT):
        super().__init__(" ".join(str(message).split()))
        self.code = code


@contextmanager
def writing(target):
    """Turn an ``OSError`` of writing ``target`` into a one-line :class:`CLIError`.

    Parameters
    ----------
    target : str or path-like
        The file or folder written, named in the message.

    Returns
    -------
    contextmanager
        Raises ``CLIError("TARGET: cannot write (REASON)")`` for an ``OSError`` inside.
    """
    try:
        yield
    except OSError as err:
        raise CLIError(f"{target}: cannot write ({err.strerror or err})") from None


def interval_text(iv: dict) -> str:
    """``[lo, hi]`` of an interval of a JSON result (see ``Interval.text``).

    Parameters
    ----------
    iv : dict
        ``estimate``, ``lower``, ``upper``, ``lower_open``, ``upper_open``.

    Returns
    -------
    str
    """
    from skinsuction.identify import Interval

    return Interval(iv["estimate"], iv["lower"], iv["upper"], iv["lower_open"],
                    iv["upper_open"]).text()


def fmt(x) -> str:
    """A number for a CSV or a ``#`` line: 10 significant digits, ``nan`` for NaN.

    Parameters
    ----------
    x : float

    Returns
    -------
    str
    """
    x = float(x)
    return "nan" if math.isnan(x) else f"{x:.10g}"


# ------------------------------------------------------------------ shared arguments
def add_measured(p: argparse.ArgumentParser, *, help: str, metavar: str = "MEASURED.csv") -> None:
    """The positional measured file (``args.measured``).

    Parameters
    ----------
    p : argparse.ArgumentParser
    help : str
        What the command reads in it.
    metavar : str

    Returns
    -------
    None
    """
    p.add_argument("measured", metavar=metavar, help=help)


def add_out(p: argparse.ArgumentParser, *, help: str, metavar: str = "DIR",
            required: bool = True) -> None:
    """``--out``: where the command writes (``args.out``).

    Parameters
    ----------
    p : argparse.ArgumentParser
    help : str
        The files written.
    metavar : str
        ``DIR`` for a folder, ``FILE`` for one file.
    required : bool

    Returns
    -------
    None
    """
    p.add_argument("--out", required=required, metavar=metavar, help=help)


def add_space(p: argparse.ArgumentParser, *, help: str, metavar: str = "DIR",
              aliases: tuple = (), dest: str = "space") -> None:
    """``--space`` (and ``aliases``): the simulated space (``args.space``, default None).

    Parameters
    ----------
    p : argparse.ArgumentParser
    help : str
        Which spaces the command takes and its default.
    metavar : str
    aliases : tuple of str
        Other flags of the same option (e.g. ``--space-dir``).
    dest : str
        The attribute of the parsed arguments (``diagnose`` keeps its ``space_dir``).

    Returns
    -------
    None
    """
    p.add_argument("--space", *aliases, dest=dest, default=None, metavar=metavar, help=help)


def add_probe(p: argparse.ArgumentParser, *, help: str, required: bool = False) -> None:
    """``--probe MM``: a probe (aperture) diameter in mm (``args.probe``, default None).

    Parameters
    ----------
    p : argparse.ArgumentParser
    help : str
    required : bool

    Returns
    -------
    None
    """
    p.add_argument("--probe", type=positive, required=required, default=None, metavar="MM",
                   help=help)


def add_bottom(p: argparse.ArgumentParser, *, help: str) -> None:
    """``--bottom``: the hypodermis/bone interface, one of :data:`BOTTOMS` (default fixed).

    Parameters
    ----------
    p : argparse.ArgumentParser
    help : str

    Returns
    -------
    None
    """
    p.add_argument("--bottom", choices=BOTTOMS, default="fixed", help=help)


def add_seed(p: argparse.ArgumentParser, *, help: str, default: int = 0) -> None:
    """``--seed``: a random seed >= 0 (``args.seed``).

    Parameters
    ----------
    p : argparse.ArgumentParser
    help : str
    default : int

    Returns
    -------
    None
    """
    p.add_argument("--seed", type=non_negative_int, default=default, help=help)


def add_repeats(p: argparse.ArgumentParser, *, default: int, help: str) -> None:
    """``--repeats``: window focusing runs, >= 1 (``args.repeats``).

    Parameters
    ----------
    p : argparse.ArgumentParser
    default : int
    help : str

    Returns
    -------
    None
    """
    p.add_argument("--repeats", type=positive_int, default=default, help=help)


def add_level(p: argparse.ArgumentParser, *, default: float, help: str) -> None:
    """``--level``: a confidence level in (0, 1) (``args.level``).

    Parameters
    ----------
    p : argparse.ArgumentParser
    default : float
    help : str

    Returns
    -------
    None
    """
    p.add_argument("--level", type=open_unit_interval, default=default, help=help)


def add_noise_um(p: argparse.ArgumentParser, *, help: str) -> None:
    """``--noise-um``: the noise sd of one deflection in µm, > 0 (``args.noise_um``, default
    None: estimated).

    Parameters
    ----------
    p : argparse.ArgumentParser
    help : str
        Where the estimate comes from when it is not given.

    Returns
    -------
    None
    """
    p.add_argument("--noise-um", type=positive, default=None, metavar="UM", help=help)


def add_geometry_arguments(p: argparse.ArgumentParser) -> None:
    """The subject's layer thicknesses, ``--no-solve`` and ``--workers`` (identify, diagnose).

    Parameters
    ----------
    p : argparse.ArgumentParser

    Returns
    -------
    None
    """
    g = p.add_argument_group(
        "the subject's layers",
        "measured on the same site (ultrasound, OCT); they override the file's header "
        "lines (# dermis_thickness_mm: 1.3). Not given: the paper's 1 mm, stated in the "
        "outputs as an assumption")
    g.add_argument("--skin", default=None, metavar="FILE",
                   help="the subject's skin as a YAML or JSON file (docs/model.md): its "
                        "dermis and hypodermis thicknesses are taken as given (the options "
                        "below override them); its moduli are what is fitted, so they are "
                        "not used. The spaces hold the paper's two layers over a fixed "
                        "bottom: another stack is refused")
    g.add_argument("--dermis-thickness-mm", type=positive, default=None, metavar="MM",
                   help="thickness of the dermis with the epidermis, mm")
    g.add_argument("--dermis-thickness-sd-mm", type=positive, default=None, metavar="MM",
                   help="its standard deviation (widens the intervals), mm")
    g.add_argument("--hypodermis-thickness-mm", type=positive, default=None, metavar="MM",
                   help="thickness of the hypodermis over the bone (fixed bottom), mm")
    g.add_argument("--hypodermis-thickness-sd-mm", type=positive, default=None, metavar="MM",
                   help="its standard deviation, mm")
    g.add_argument("--no-solve", action="store_true",
                   help="refuse a probe or layers the simulated space lacks instead of reading "
                        "their rays off the geometry space or solving them on demand (16 FE "
                        "rays a probe, 10-40 s of CPU, cached in $SKINSUCTION_CACHE or "
                        "~/.cache/skinsuction)")
    g.add_argument("--solve-rays", action="store_true",
                   help="solve every ray at the subject's probe and layers instead of reading "
                        "the geometry space (the FE reference: minutes instead of seconds)")
    g.add_argument("--workers", type=positive_int, default=1,
                   help="processes for rays solved on demand (default 1)")


def solve_from_args(args: argparse.Namespace):
    """``solve_on_demand`` from ``--no-solve`` and ``--solve-rays``: False, True or "always".

    Parameters
    ----------
    args : argparse.Namespace

    Returns
    -------
    bool or str
    """
    if args.no_solve and args.solve_rays:
        raise SystemExit("--no-solve and --solve-rays contradict each other: give one")
    return False if args.no_solve else ("always" if args.solve_rays else True)


def thickness_from_args(args: argparse.Namespace) -> dict:
    """The thickness keywords of :func:`skinsuction.measured.geometry_of` from parsed options.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed by a parser with :func:`add_geometry_arguments`.

    Returns
    -------
    dict
        The thicknesses given (keys of :data:`THICKNESS_KEYS`); empty if none. A
        ``--skin`` file gives the dermis and hypodermis thicknesses, the options
        override it.

    Raises
    ------
    CLIError
        A skin file the model refuses, or one that is not a dermis over a hypodermis
        on a fixed bottom (what the simulated spaces hold).

    Examples
    --------
    >>> ns = argparse.Namespace(skin=None, dermis_thickness_mm=1.3)
    >>> thickness_from_args(ns)
    {'dermis_thickness_mm': 1.3}
    """
    out = {}
    if getattr(args, "skin", None):
        from skinsuction.model import ParameterError, Skin

        try:
            skin = Skin.read(args.skin)
            values = skin.two_layer_values()
        except ParameterError as err:
            raise CLIError(f"--skin {args.skin}: {err} (the simulated spaces hold the "
                           "paper's dermis over hypodermis)") from None
        if skin.bottom != "fixed":
            raise CLIError(f"--skin {args.skin}: bottom {skin.bottom!r}: the simulated "
                           "spaces hold a fixed bottom")
        out = {"dermis_thickness_mm": values["t_d"], "hypodermis_thickness_mm": values["t_h"]}
    out.update({k: getattr(args, k) for k in THICKNESS_KEYS
                if getattr(args, k, None) is not None})
    return out
