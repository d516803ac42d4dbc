"""``skinsuction simulate``: the FE suction curve M(p) at one parameter point.

::

    skinsuction simulate --probe 6 --x1d 0.08 --x1h 4.1e-4 [--out curve.csv]

Prints (or writes atomically with ``--out``) the apex deflection curve as CSV after
``#`` lines with the settings and the solver's outcome; exit code 3 if the solver
stopped before the last pressure (the curve is still written, NaN beyond).
Every argument is defined in :func:`add_arguments`, and :func:`curve_csv` writes
every one of them into the ``#`` lines.
"""

from __future__ import annotations

import argparse
import sys

from skinsuction._argtypes import non_negative, positive, refinement

from ._common import (
    EXIT_NOT_CONVERGED,
    EXIT_OK,
    CLIError,
    add_bottom,
    add_out,
    add_probe,
    fmt,
    writing,
)

__all__ = ["HELP", "DESCRIPTION", "add_arguments", "run", "curve_csv", "PROGRESS_QUIET_S"]

HELP = "FE suction curve M(p) at one parameter point"

DESCRIPTION = (
    "Run the axisymmetric two-layer FE model of the suction test (pressures 0, 2, "
    "..., 100 mbar) and print the apex deflection curve as CSV "
    "(pressure_mbar,deflection_mm) after '#' comment lines with the settings and "
    "the solver outcome (# converged: true|false, # last_converged_mbar, # reason). "
    "Exit code 0 if every pressure converged, 3 if the solver stopped early "
    "(the curve is still written, NaN beyond the last converged pressure).")

#: seconds before `simulate` shows its progress (a default-mesh curve takes about 1 s)
PROGRESS_QUIET_S = 2.0


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Every argument of ``skinsuction simulate``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser.

    Returns
    -------
    None
    """
    add_probe(p, required=True, help="aperture (probe) diameter in mm, e.g. 6 or 2")
    p.add_argument("--x1d", type=positive, required=True, metavar="MPA",
                   help="dermis modulus X1 in MPa (W = X1 (I1-3) + X2 (I1-3)^2), e.g. 0.08")
    p.add_argument("--x1h", type=positive, required=True, metavar="MPA",
                   help="hypodermis modulus X1 in MPa, e.g. 4.1e-4")
    p.add_argument("--x2d", type=non_negative, default=0.0, metavar="MPA",
                   help="dermis second-order modulus X2 in MPa (default 0: neo-Hookean)")
    p.add_argument("--x2h", type=non_negative, default=0.0, metavar="MPA",
                   help="hypodermis second-order modulus X2 in MPa (default 0: neo-Hookean)")
    p.add_argument("--td", type=positive, default=1.0, metavar="MM",
                   help="thickness of the dermis (with the epidermis) in mm (default 1)")
    p.add_argument("--th", type=positive, default=1.0, metavar="MM",
                   help="thickness of the hypodermis in mm (default 1)")
    add_bottom(p, help="hypodermis/bone interface: fixed = restrained laterally and axially, "
                       "axial = restrained axially only, free = not restrained "
                       "(default fixed, as in the paper's identifications)")
    p.add_argument("--refinement", type=refinement, default=1.0, metavar="FACTOR",
                   help="mesh density factor, dimensionless: 1 = reference mesh, "
                        "2 = element sizes halved, 0.5 = doubled; a number in [0.25, 1] or "
                        "a whole number 2..8 (default 1)")
    p.add_argument("--measured-format", action="store_true",
                   help="write the curve in the measured-CSV format (columns probe_mm, "
                        "pressure_mbar, deflection_mm), which identify, diagnose and study "
                        "read; the '#' lines are the same")
    add_out(p, metavar="FILE", required=False,
            help="write the CSV to FILE (atomically) instead of standard output")


def curve_csv(curve, args: argparse.Namespace) -> str:
    """The CSV text of a simulated curve: ``#`` lines (settings, solver outcome), then rows.

    Parameters
    ----------
    curve : skinsuction.model.Curve
        The simulated curve (pressures, deflections, convergence, solver counts).
    args : argparse.Namespace
        The parsed arguments of :func:`add_arguments`.

    Returns
    -------
    str
        ``pressure_mbar,deflection_mm`` rows (NaN beyond the last converged pressure),
        or with ``--measured-format`` ``probe_mm,pressure_mbar,deflection_mm`` rows of
        the converged points only.
    """
    from skinsuction import __version__

    lines = [
        f"# skinsuction simulate {__version__}: apex deflection M(p) of the suction test",
        f"# probe_mm: {fmt(args.probe)}",
        f"# x1d_mpa: {fmt(args.x1d)}",
        f"# x1h_mpa: {fmt(args.x1h)}",
        f"# x2d_mpa: {fmt(args.x2d)}",
        f"# x2h_mpa: {fmt(args.x2h)}",
        f"# t_d_mm: {fmt(args.td)}",
        f"# t_h_mm: {fmt(args.th)}",
        f"# bottom: {args.bottom}",
        f"# refinement: {fmt(args.refinement)}",
        f"# converged: {'true' if curve.converged else 'false'}",
        f"# last_converged_mbar: {fmt(curve.last_converged_mbar)}",
        f"# reason: {' '.join(str(curve.reason or '').split())}",
        f"# newton_iterations: {int(curve.newton_iterations or 0)}",
        f"# dofs: {int(curve.dofs or 0)}",
        f"# seconds: {float(curve.seconds or 0.0):.3f}",
    ]
    rows = zip(curve.pressure_mbar, curve.deflection_mm)
    if getattr(args, "measured_format", False):
        # a measured file has no NaN rows: the curve stops where the solver stopped
        lines.append("probe_mm,pressure_mbar,deflection_mm")
        lines += [f"{fmt(args.probe)},{fmt(p)},{fmt(m)}" for p, m in rows if m == m]
    else:
        lines.append("pressure_mbar,deflection_mm")
        lines += [f"{fmt(p)},{fmt(m)}" for p, m in rows]
    return "\n".join(lines) + "\n"


def run(args: argparse.Namespace) -> int:
    """Run ``skinsuction simulate``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments of :func:`add_arguments`.

    Returns
    -------
    int
        0 if every pressure converged, 3 if the solver stopped early.
    """
    from skinsuction import model
    from skinsuction._progress import Progress

    # a fine mesh takes minutes: a bar on a terminal, a line every 10 s in a log
    bar = Progress(len(model.DEFAULT_PRESSURES_MBAR) - 1, "simulate", "pressures",
                   quiet_below=PROGRESS_QUIET_S)
    try:
        curve = model.simulate(
            args.x1d, args.x1h, args.x2d, args.x2h, args.td, args.th, args.probe, args.bottom,
            pressures_mbar=None, mesh={"refinement": args.refinement},
            progress=lambda k, n, p: bar.step(note=f"{p:g} mbar"),
        )
    except ValueError as err:  # parameters the model refuses
        raise CLIError(f"the model refused the parameters: {err}") from None
    finally:
        bar.close()
    text = curve_csv(curve, args)
    if args.out:
        from skinsuction._files import atomic_output

        with writing(args.out), atomic_output(args.out) as tmp:
            tmp.write_text(text, encoding="utf-8")
    else:
        sys.stdout.write(text)
        sys.stdout.flush()
    if not curve.converged:
        print(f"skinsuction simulate: warning: the solver stopped at "
              f"{fmt(curve.last_converged_mbar)} mbar ({curve.reason}); "
              "the curve is NaN beyond", file=sys.stderr)
        return EXIT_NOT_CONVERGED
    return EXIT_OK
