"""``skinsuction diagnose``: where the neo-Hookean model misfits measured curves, and why.

::

    skinsuction diagnose MEASURED.csv --out DIR [--space DIR]
        [--noise-um SD] [--alpha 0.01] [--delta-bic -10] [--seed 0] [--repeats 2]
        [--dermis-thickness-mm MM] [--hypodermis-thickness-mm MM] [--no-solve]

The file is read once (:func:`skinsuction.measured.read_measurement`): pressure
ramps go to :func:`skinsuction.diagnose.diagnose_file`, time curves to
:func:`skinsuction.diagnose.diagnose_time_file`.  Bad input (file, spaces)
raises ``ValueError`` subclasses with one-line messages
(:class:`skinsuction.measured.MeasuredDataError`,
:class:`skinsuction.errors.InputError`), which the command line prints with
exit code 2.
"""

from __future__ import annotations

import argparse
import sys
from contextlib import contextmanager

from skinsuction._argtypes import negative, non_negative, open_unit_interval

from ._common import (
    EXIT_OK,
    add_geometry_arguments,
    add_level,
    add_measured,
    add_noise_um,
    add_out,
    add_repeats,
    add_seed,
    add_space,
    solve_from_args,
    thickness_from_args,
    writing,
)

__all__ = ["HELP", "DESCRIPTION", "add_arguments", "run"]

HELP = "show where the neo-Hookean model misfits measured curves, name the cause"

DESCRIPTION = (
    "Fit the two-layer neo-Hookean model to measured suction curves (one or both "
    "probes), test the residuals for a systematic misfit against the noise, fit "
    "each candidate extension (strain stiffening, dermis thickness, pre-tension) "
    "on the ray spaces built by the workflow, compare them by E, BIC and a "
    "cross-probe holdout, and name the cause (or none). Writes DIR/report.json, "
    "DIR/report.md and figures.")


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Every argument of ``skinsuction diagnose`` (defaults from ``diagnose.Settings``).

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser.

    Returns
    -------
    None
    """
    from skinsuction.diagnose import Settings

    d = Settings()
    add_measured(p, help="measured curves, the format of `skinsuction identify`: columns "
                         "probe_mm, pressure_mbar, deflection_mm and optionally curve "
                         "(replicate id); one or more probes (2-8 mm); header lines may give "
                         "the layer thicknesses (# dermis_thickness_mm: 1.3)")
    add_out(p, help="output folder: report.json, report.md, fit.png/pdf, "
                    "residuals.png/pdf, gain.png/pdf")
    add_space(p, aliases=("--space-dir",), dest="space_dir",
              help="folder of the scale-free simulated space (neo_hookean.parquet and one "
                   "file per cause). Default: results/simulated_space/scale_free if the "
                   "workflow has built it under the working directory (`snakemake "
                   "--cores 2 scale_free_space`), else the default space shipped with "
                   "skinsuction; the space used is printed and recorded in report.json "
                   "(input.space) and report.md")
    add_noise_um(p, help="noise sd of one measured deflection in µm, if known (default: "
                         "estimated from replicate curves, or from the curves' differences)")
    p.add_argument("--alpha", type=open_unit_interval, default=d.alpha,
                   help=f"level of the systematic-misfit test (default {d.alpha:g})")
    p.add_argument("--delta-bic", type=negative, default=d.delta_bic, metavar="DB",
                   help="BIC difference a cause must reach to earn its extra parameter "
                        f"(default {d.delta_bic:g}: very strong evidence)")
    p.add_argument("--model-error-um", type=non_negative, default=d.model_error_um,
                   metavar="UM", help="accuracy of the simulated spaces in µm, added in "
                                      f"quadrature to the noise (default {d.model_error_um:g})")
    p.add_argument("--pattern-gate", action=argparse.BooleanOptionalAction,
                   default=d.pattern_gate,
                   help="name a cause only once the smooth-pattern test of the neo-Hookean "
                        "residuals fires (--no-pattern-gate: a candidate that lowers the BIC "
                        "by --delta-bic and removes the misfit is a detection of its own; "
                        f"default {'on' if d.pattern_gate else 'off'})")
    add_repeats(p, default=d.repeats,
                help=f"window focusing runs per fit (default {d.repeats})")
    add_seed(p, default=d.seed,
             help="random seed, >= 0; the same seed gives the same report (default 0)")
    add_level(p, default=d.level,
              help="confidence level of the profile-likelihood intervals of every fit "
                   f"(default {d.level:g})")
    p.add_argument("--fe-correction", type=int, choices=range(6), default=d.fe_correction,
                   metavar="STEPS",
                   help="time curves: steps of the FE correction of every fit with creep "
                        "(FE time solves at the fit remove the fast path's error; 0: the "
                        f"fast path alone; default {d.fe_correction})")
    p.add_argument("--no-holdout", action="store_true",
                   help="skip the cross-probe holdout (faster)")
    add_geometry_arguments(p)


def run(args: argparse.Namespace) -> int:
    """Run ``skinsuction diagnose``: a pressure ramp or time curves, by the file.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments of :func:`add_arguments`.

    Returns
    -------
    int
        0 (errors raise, and the command line prints them).
    """
    from skinsuction.diagnose import Settings, diagnose_file, write_report
    from skinsuction.measured import MeasuredTimeData, read_measurement

    settings = Settings(alpha=args.alpha, delta_bic=args.delta_bic, noise_um=args.noise_um,
                        model_error_um=args.model_error_um, repeats=args.repeats,
                        seed=args.seed, holdout=not args.no_holdout,
                        level=args.level, pattern_gate=args.pattern_gate,
                        fe_correction=args.fe_correction)
    data = read_measurement(args.measured)
    if isinstance(data, MeasuredTimeData):
        return _run_time(args, settings, data)
    with _space_errors():
        report = diagnose_file(data, args.space_dir, settings,
                               thickness=thickness_from_args(args),
                               on_demand={False: False, True: None}.get(
                                   solve_from_args(args), "always"),
                               workers=args.workers)
    with writing(args.out):
        paths = write_report(report, args.out)
    space = (report.get("input") or {}).get("space") or {}
    if space.get("description"):
        print(f"space: {space['description']}")
    print(report["summary"])
    print(f"baseline: {report['baseline']['description']}")
    print(f"wrote {', '.join(str(p) for p in paths.values())}")
    sys.stdout.flush()
    return EXIT_OK


def _run_time(args: argparse.Namespace, settings, data) -> int:
    """``diagnose`` of time curves: is it creep?"""
    from skinsuction.diagnose import diagnose_time_file, write_time_report

    with _space_errors():
        report = diagnose_time_file(data, args.space_dir, settings,
                                    thickness=thickness_from_args(args),
                                    solve_on_demand=solve_from_args(args),
                                    workers=args.workers)
    with writing(args.out):
        paths = write_time_report(report, args.out)
    for w in report["warnings"]:
        print(f"warning: {w}", file=sys.stderr)
    print(report["summary"])
    print(f"wrote {', '.join(str(p) for p in paths.values())}")
    sys.stdout.flush()
    return EXIT_OK


@contextmanager
def _space_errors():
    """A missing or unreadable space as an :class:`~skinsuction.errors.InputError` (exit 2)."""
    from skinsuction.errors import InputError
    from skinsuction.space import SpaceFileError, SpaceMissingError

    try:
        yield
    except (SpaceMissingError, SpaceFileError) as err:
        raise InputError(str(err)) from None
