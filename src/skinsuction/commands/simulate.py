"""``skinsuction simulate``: the FE suction curve M(p) of one skin under one probe.

::

    skinsuction simulate --probe 6 --x1d 0.08 --x1h 4.1e-4 [--out curve.csv]
    skinsuction simulate --probe 2 --skin skin.yaml [--max-mbar 450 --step-mbar 10]

The skin is a file (``--skin``: any stack of one to four layers, see
:class:`skinsuction.model.Skin`) or the paper's two layers from the shortcuts
``--x1d --x1h [--x2d --x2h --td --th]``.

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

__all__ = ["HELP", "DESCRIPTION", "add_arguments", "add_skin_arguments", "run", "curve_csv",
           "skin_from_args", "PROGRESS_QUIET_S"]

HELP = "FE suction curve M(p) of one skin under one probe"

DESCRIPTION = (
    "Run the axisymmetric FE model of the suction test on a skin (--skin FILE.yaml: any "
    "stack of 1-4 layers; or the paper's two layers from --x1d --x1h ...) under a ramp "
    "(default 0, 2, ..., 100 mbar) and print the apex deflection curve as CSV "
    "(pressure_mbar,deflection_mm) after '#' comment lines with the settings and "
    "the solver outcome (# converged: true|false, # last_converged_mbar, # reason). "
    "Exit code 0 if every pressure converged, 3 if the solver stopped early "
    "(the curve is still written, NaN beyond the last converged pressure).")

#: seconds before `simulate` shows its progress (a default-mesh curve takes about 1 s)
PROGRESS_QUIET_S = 2.0


#: the two-layer shortcuts and their defaults (None: not given)
SHORTCUTS = {"x1d": None, "x1h": None, "x2d": 0.0, "x2h": 0.0, "td": 1.0, "th": 1.0}


def add_skin_arguments(p: argparse.ArgumentParser) -> None:
    """The skin, probe and ramp arguments (shared by ``simulate`` and ``export-inp``).

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser.

    Returns
    -------
    None
    """
    add_probe(p, required=True, help="aperture (probe) diameter in mm, e.g. 6 or 2")
    p.add_argument("--skin", metavar="FILE",
                   help="the skin as a YAML or JSON file: layers (top first: name, thickness "
                        "mm, X1, X2 MPa, prestretch, spectrum) and bottom; instead of the "
                        "two-layer shortcuts below (see docs/model.md)")
    p.add_argument("--x1d", type=positive, default=None, metavar="MPA",
                   help="dermis modulus X1 in MPa (W = X1 (I1-3) + X2 (I1-3)^2), e.g. 0.08")
    p.add_argument("--x1h", type=positive, default=None, metavar="MPA",
                   help="hypodermis modulus X1 in MPa, e.g. 4.1e-4")
    p.add_argument("--x2d", type=non_negative, default=None, metavar="MPA",
                   help="dermis second-order modulus X2 in MPa (default 0: neo-Hookean)")
    p.add_argument("--x2h", type=non_negative, default=None, metavar="MPA",
                   help="hypodermis second-order modulus X2 in MPa (default 0: neo-Hookean)")
    p.add_argument("--td", type=positive, default=None, metavar="MM",
                   help="thickness of the dermis (with the epidermis) in mm (default 1)")
    p.add_argument("--th", type=positive, default=None, metavar="MM",
                   help="thickness of the hypodermis in mm (default 1)")
    add_bottom(p, help="hypodermis/bone interface: fixed = restrained laterally and axially, "
                       "axial = restrained axially only, free = not restrained "
                       "(default fixed, as in the paper's identifications; with --skin, "
                       "the file's unless given)")
    p.set_defaults(bottom=None)  # a skin file's bottom stands unless --bottom is given
    p.add_argument("--max-mbar", type=positive, default=100.0, metavar="MBAR",
                   help="largest suction of the ramp in mbar (default 100; Cutometers "
                        "apply up to 500)")
    p.add_argument("--step-mbar", type=positive, default=2.0, metavar="MBAR",
                   help="pressure step of the ramp in mbar (default 2)")
    p.add_argument("--refinement", type=refinement, default=1.0, metavar="FACTOR",
                   help="mesh density factor, dimensionless: 1 = reference mesh, "
                        "2 = element sizes halved, 0.5 = doubled; a number in [0.25, 1] or "
                        "a whole number 2..8 (default 1)")


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
    add_skin_arguments(p)
    p.add_argument("--measured-format", action="store_true",
                   help="write the curve in the measured-CSV format (columns probe_mm, "
                        "pressure_mbar, deflection_mm), which identify, diagnose and study "
                        "read; the '#' lines are the same")
    add_out(p, metavar="FILE", required=False,
            help="write the CSV to FILE (atomically) instead of standard output")


def skin_from_args(args: argparse.Namespace):
    """The skin and the ramp the arguments describe.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments of :func:`add_skin_arguments`.

    Returns
    -------
    (skinsuction.model.Skin, skinsuction.model.Ramp)

    Raises
    ------
    CLIError
        Both ``--skin`` and a shortcut, neither, or a skin or ramp the model refuses.
    """
    from skinsuction.model import ParameterError, Ramp, Skin

    given = [f"--{k}" for k in SHORTCUTS if getattr(args, k, None) is not None]
    try:
        ramp = Ramp(args.max_mbar, args.step_mbar)
        if args.skin:
            if given:
                raise CLIError(f"give the skin either as --skin {args.skin} or by the "
                               f"two-layer shortcuts, not both ({', '.join(given)})")
            skin = Skin.read(args.skin)
            if args.bottom is not None and args.bottom != skin.bottom:
                skin = Skin(skin.layers, args.bottom)
            return skin, ramp
        missing = [f"--{k}" for k in ("x1d", "x1h") if getattr(args, k) is None]
        if missing:
            raise CLIError(f"the skin needs --skin FILE or {' and '.join(missing)}")
        values = {k: v if getattr(args, k) is None else getattr(args, k)
                  for k, v in SHORTCUTS.items()}
        skin = Skin.two_layer(values["x1d"], values["x1h"], values["x2d"], values["x2h"],
                              values["td"], values["th"], args.bottom or "fixed")
        return skin, ramp
    except ParameterError as err:
        raise CLIError(f"the model refused the parameters: {err}") from None


def curve_csv(curve, args: argparse.Namespace, skin=None) -> str:
    """The CSV text of a simulated curve: ``#`` lines (settings, solver outcome), then rows.

    Parameters
    ----------
    curve : skinsuction.model.Curve
        The simulated curve (pressures, deflections, convergence, solver counts).
    args : argparse.Namespace
        The parsed arguments of :func:`add_arguments`.
    skin : skinsuction.model.Skin, optional
        The skin solved (default: the one the arguments describe).

    Returns
    -------
    str
        ``pressure_mbar,deflection_mm`` rows (NaN beyond the last converged pressure),
        or with ``--measured-format`` ``probe_mm,pressure_mbar,deflection_mm`` rows of
        the converged points only.
    """
    import json

    from skinsuction import __version__
    from skinsuction.model import ParameterError

    if skin is None:
        skin, _ = skin_from_args(args)
    lines = [
        f"# skinsuction simulate {__version__}: apex deflection M(p) of the suction test",
        f"# probe_mm: {fmt(args.probe)}",
    ]
    try:  # the paper's two layers keep the header lines they always had
        v = skin.two_layer_values()
        lines += [f"# x1d_mpa: {fmt(v['x1d'])}", f"# x1h_mpa: {fmt(v['x1h'])}",
                  f"# x2d_mpa: {fmt(v['x2d'])}", f"# x2h_mpa: {fmt(v['x2h'])}",
                  f"# t_d_mm: {fmt(v['t_d'])}", f"# t_h_mm: {fmt(v['t_h'])}"]
    except ParameterError:
        pass
    lines += [
        f"# skin: {json.dumps(skin.to_dict(), separators=(',', ':'))}",
        f"# bottom: {skin.bottom}",
        f"# ramp_mbar: 0 to {fmt(args.max_mbar)} by {fmt(args.step_mbar)}",
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

    skin, ramp = skin_from_args(args)
    # a fine mesh takes minutes: a bar on a terminal, a line every 10 s in a log
    bar = Progress(len(ramp.pressures_mbar) - 1, "simulate", "pressures",
                   quiet_below=PROGRESS_QUIET_S)
    try:
        curve = model.simulate(
            skin, args.probe, pressures_mbar=ramp.pressures_mbar,
            mesh={"refinement": args.refinement},
            progress=lambda k, n, p: bar.step(note=f"{p:g} mbar"),
        )
    except ValueError as err:  # parameters the model refuses
        raise CLIError(f"the model refused the parameters: {err}") from None
    finally:
        bar.close()
    text = curve_csv(curve, args, skin)
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
