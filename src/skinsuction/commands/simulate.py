"""``skinsuction simulate``: the FE suction curve of one skin under one probe, M(p) or M(t).

::

    skinsuction simulate --probe 6 --x1d 0.08 --x1h 4.1e-4 [--out curve.csv]
    skinsuction simulate --probe 2 --skin skin.yaml [--max-mbar 450 --step-mbar 10]
    skinsuction simulate --probe 2 --skin skin.yaml --mode1 450,3,3,2 [--rparams]
    skinsuction simulate --probe 2 --skin skin.yaml (--mode2 450,3,3,1 | --history p.csv)

The skin is a file (``--skin``: any stack of one to four layers, see
:class:`skinsuction.model.Skin`) or the paper's two layers from the shortcuts
``--x1d --x1h [--x2d --x2h --td --th]``.

Prints (or writes atomically with ``--out``) the apex deflection curve as CSV after
``#`` lines with the settings and the solver's outcome; exit code 3 if the solver
stopped before the last pressure (the curve is still written, NaN beyond).
A time protocol (``--mode1``, ``--mode2``, ``--history``; :mod:`._protocols`) runs
the model in time with each layer's spectrum and writes ``time_s,pressure_mbar,
deflection_mm`` sampled at ``--sample-hz``. Every argument is defined in
:func:`add_arguments`; :func:`curve_csv` (a ramp) and
:func:`skinsuction.commands._protocols.time_csv` write them into the ``#`` lines.
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
from ._protocols import TIME_OPTIONS, header_lines

__all__ = ["HELP", "DESCRIPTION", "add_arguments", "add_skin_arguments", "run", "curve_csv",
           "skin_from_args", "PROGRESS_QUIET_S"]

HELP = "FE suction curve of one skin under one probe: M(p), or in time (mode 1, mode 2)"

DESCRIPTION = (
    "Run the axisymmetric FE model of the suction test on a skin (--skin FILE.yaml: any "
    "stack of 1-4 layers; or the paper's two layers from --x1d --x1h ...) under a ramp "
    "(default 0, 2, ..., 100 mbar) and print the apex deflection curve as CSV "
    "(pressure_mbar,deflection_mm) after '#' comment lines with the settings and "
    "the solver outcome (# converged: true|false, # last_converged_mbar, # reason). "
    "With a time protocol (--mode1, --mode2 or --history) it runs the model in time, "
    "each layer with its relaxation spectrum, and prints time_s,pressure_mbar,"
    "deflection_mm sampled at --sample-hz. "
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


class _Default(float):
    """A ramp default the user did not type: a time protocol refuses only typed ones."""


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
    p.set_defaults(max_mbar=_Default(100.0), step_mbar=_Default(2.0))
    g = p.add_argument_group(
        "time protocols",
        "instead of the ramp, at most one of these: the model in time, each layer with its "
        "relaxation spectrum (an elastic skin follows the load quasi-statically)")
    g.add_argument("--mode1", metavar="P,ON,OFF,CYCLES", default=None,
                   help="Cutometer mode 1: suction P mbar held ON s, released OFF s, CYCLES "
                        "times (each switch a 0.01 s ramp), e.g. 450,3,3,2")
    g.add_argument("--mode2", metavar="P,RISE,FALL,CYCLES", default=None,
                   help="Cutometer mode 2: suction rising linearly to P mbar over RISE s and "
                        "back to 0 over FALL s, CYCLES times back to back, e.g. 450,3,3,1")
    g.add_argument("--history", metavar="FILE", default=None,
                   help="any suction history: a CSV with the header time_s,pressure_mbar (s, "
                        "mbar; times increasing, suction >= 0 and 0 at the first time), "
                        "piecewise linear between its rows")
    g.add_argument("--sample-hz", type=positive, default=None, metavar="HZ",
                   help="sampling rate of the time curve in Hz (default 100, as a Cutometer); "
                        "every sample is a time step of the solver")
    g.add_argument("--rparams", action="store_true",
                   help="with --mode1: print the R parameters (Ue, Uv, Uf, Ur, Ua in mm, "
                        "R0-R9 per cycle) of the simulated curve, as skinsuction rparams "
                        "computes them (after the curve on standard output, alone when the "
                        "curve goes to a file)")
    p.add_argument("--measured-format", action="store_true",
                   help="write the curve in the measured-CSV format (columns probe_mm, "
                        "pressure_mbar, deflection_mm; with a time protocol probe_mm, time_s, "
                        "pressure_mbar, deflection_mm), which identify, diagnose, study and "
                        "rparams read; the '#' lines are the same")
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
    if skin is None:
        skin, _ = skin_from_args(args)
    lines = header_lines("apex deflection M(p) of the suction test", skin, args.probe)
    lines += [
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
        0 if every pressure (or time) converged, 3 if the solver stopped early.
    """
    from skinsuction import model
    from skinsuction._progress import Progress

    protocol = _time_protocol(args)
    skin, ramp = skin_from_args(args)
    if protocol is not None:
        return _run_time(args, skin, protocol)
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
    _emit(curve_csv(curve, args, skin), args)
    if not curve.converged:
        print(f"skinsuction simulate: warning: the solver stopped at "
              f"{fmt(curve.last_converged_mbar)} mbar ({curve.reason}); "
              "the curve is NaN beyond", file=sys.stderr)
        return EXIT_NOT_CONVERGED
    return EXIT_OK


def _time_protocol(args):
    """The time protocol of the options (None: the ramp), after the exclusions."""
    from ._protocols import protocol_from_args

    given = [f"--{k}" for k in TIME_OPTIONS if getattr(args, k, None) is not None]
    if len(given) > 1:
        raise CLIError(f"give one protocol, not {' and '.join(given)}")
    if not given:
        if getattr(args, "sample_hz", None) is not None:
            raise CLIError("--sample-hz applies to a time protocol (--mode1, --mode2, "
                           "--history), not to the ramp")
        if getattr(args, "rparams", False):
            raise CLIError("--rparams needs --mode1 (R0-R9 are read from cycles at a "
                           "constant suction)")
        return None
    typed = [f"--{k.replace('_', '-')}" for k in ("max_mbar", "step_mbar")
             if not isinstance(getattr(args, k), _Default)]
    if typed:
        raise CLIError(f"{' and '.join(typed)} set the ramp; {given[0]} sets the suction in "
                       "time: give one protocol")
    if args.rparams and given != ["--mode1"]:
        raise CLIError(f"--rparams needs --mode1, not {given[0]} (R0-R9 are read from "
                       "cycles at a constant suction)")
    return protocol_from_args(args)


def _run_time(args, skin, protocol) -> int:
    """Solve a time protocol, write its curve (and print its R parameters)."""
    from skinsuction._progress import Progress

    from ._protocols import (DEFAULT_SAMPLE_HZ, rparams_text, simulate_protocol, solve_grid,
                             time_csv)

    hz = args.sample_hz or DEFAULT_SAMPLE_HZ
    # the solver's times: the protocol's own points and every sample
    bar = Progress(solve_grid(protocol)[0].size - 1, "simulate", "time steps",
                   quiet_below=PROGRESS_QUIET_S)
    try:
        result = simulate_protocol(skin, args.probe, protocol, args.refinement,
                                   lambda k, n, t: bar.step(note=f"{t:g} s"))
    finally:
        bar.close()
    history = result[0]

    def text(measured):
        return time_csv(skin, args.probe, protocol, result, args.refinement, hz, measured)

    _emit(text(args.measured_format), args)
    if not history.converged:
        reached = history.times_s[history.deflection_mm == history.deflection_mm][-1]
        print(f"skinsuction simulate: warning: the solver stopped at {reached:g} s "
              f"({history.reason}); the curve is NaN beyond"
              + ("; no R parameters" if args.rparams else ""), file=sys.stderr)
        return EXIT_NOT_CONVERGED
    if args.rparams:
        sys.stdout.write(("\n" if not args.out else "") + rparams_text(text(True)))
        sys.stdout.flush()
    return EXIT_OK


def _emit(text: str, args) -> None:
    """Write the CSV to ``--out`` (atomically) or standard output."""
    if args.out:
        from skinsuction._files import atomic_output

        with writing(args.out), atomic_output(args.out) as tmp:
            tmp.write_text(text, encoding="utf-8")
    else:
        sys.stdout.write(text)
        sys.stdout.flush()
