"""``skinsuction export-inp``: the Abaqus/CalculiX input deck of one skin under one probe.

::

    skinsuction export-inp --probe 2 --skin skin.yaml --out suction.inp
    skinsuction export-inp --probe 6 --x1d 0.08 --x1h 4.1e-4 --out suction.inp
    ccx suction            # CalculiX; the apex deflection (set APEX, U2) is in suction.dat

The deck is this model's mesh (8-node axisymmetric elements with reduced integration,
CAX8R), one material per layer, the glued face, axis and bottom as node sets, and the
suction as a follower pressure on the free surface inside the aperture, in plain
Abaqus syntax, so the model can be checked in the FE code a user trusts
(docs/calculix.md). What it leaves out is said on standard error and in the deck.
"""

from __future__ import annotations

import argparse
import sys

from ._common import EXIT_OK, CLIError, add_out, writing
from .simulate import add_skin_arguments, skin_from_args

__all__ = ["HELP", "DESCRIPTION", "add_arguments", "run"]

HELP = "Abaqus/CalculiX input deck of one skin under one probe"

DESCRIPTION = (
    "Write the input deck (.inp, plain Abaqus syntax; runs in CalculiX and Abaqus) of the "
    "suction test on a skin (--skin FILE.yaml or the two-layer shortcuts) under a ramp: "
    "the same mesh, materials, boundary conditions and follower suction as "
    "`skinsuction simulate`, without the probe wall contact (said on stderr).")


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Every argument of ``skinsuction export-inp``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser.

    Returns
    -------
    None
    """
    add_skin_arguments(p)
    p.add_argument("--unit", choices=("Pa", "kPa", "MPa"), default="Pa",
                   help="unit of the moduli and the pressure in the deck (lengths in mm); "
                        "Pa by default, so the solver's force-based convergence test is a "
                        "real one for this soft problem (docs/calculix.md)")
    add_out(p, metavar="FILE", required=True, help="the .inp file to write (atomically)")


def run(args: argparse.Namespace) -> int:
    """Run ``skinsuction export-inp``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments of :func:`add_arguments`.

    Returns
    -------
    int
        0 when the deck is written.
    """
    from skinsuction.model import ParameterError, SuctionTest, write_inp

    skin, ramp = skin_from_args(args)
    try:
        model = SuctionTest(skin, args.probe, {"refinement": args.refinement,
                                               "probe_wall": False})
        with writing(args.out):
            path = write_inp(model, args.out, ramp.pressures_mbar, stress_unit=args.unit)
    except ParameterError as err:
        raise CLIError(f"the deck cannot carry this model: {err}") from None
    print(f"skinsuction export-inp: note: the deck leaves out the probe wall contact (a "
          f"frictionless wall at r = a, touched only by very soft skin); compare it with "
          f"this model without the wall. Wrote {path}", file=sys.stderr)
    return EXIT_OK
