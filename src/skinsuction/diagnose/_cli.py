"""``skinsuction diagnose``: arguments and run, for the CLI's command registry.

::

    skinsuction diagnose MEASURED.csv --out DIR [--space DIR]
        [--noise-um SD] [--alpha 0.01] [--delta-bic -10] [--seed 0] [--repeats 2]
        [--dermis-thickness-mm MM] [--hypodermis-thickness-mm MM] [--no-solve]

Bad input (file, spaces) raises ``ValueError`` subclasses with one-line messages
(:class:`skinsuction.measured.MeasuredDataError`,
:class:`skinsuction.errors.InputError`), which the CLI prints
with exit code 2.
"""

from __future__ import annotations

import argparse
import sys

from skinsuction._argtypes import non_negative, non_negative_int, number, positive, positive_int

from skinsuction.measured._geometry import add_geometry_arguments, thickness_from_args

from ._diagnose import Settings

__all__ = ["add_arguments", "command"]


def _level(text):
    v = positive(text)
    if not v < 1:
        raise argparse.ArgumentTypeError(f"must lie in (0, 1), got {text}")
    return v


def _negative(text):
    v = number(text)
    if not v < 0:
        raise argparse.ArgumentTypeError(f"must be negative, got {text}")
    return v


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Arguments of ``skinsuction diagnose``."""
    d = Settings()
    p.add_argument("measured", metavar="MEASURED.csv",
                   help="measured curves, the format of `skinsuction identify`: columns "
                        "probe_mm, pressure_mbar, deflection_mm and optionally curve "
                        "(replicate id); one or more probes (2-8 mm); header lines may give the layer "
                        "thicknesses (# dermis_thickness_mm: 1.3)")
    p.add_argument("--out", required=True, metavar="DIR",
                   help="output folder: report.json, report.md, fit.png/pdf, "
                        "residuals.png/pdf, gain.png/pdf")
    p.add_argument("--space", "--space-dir", dest="space_dir", default=None,
                   metavar="DIR",
                   help="folder of the scale-free simulated space (neo_hookean.parquet and one "
                        "file per cause). Default: results/simulated_space/scale_free if the "
                        "workflow has built it under the working directory (`snakemake "
                        "--cores 2 scale_free_space`), else the default space shipped with "
                        "skinsuction; the space used is printed and recorded in report.json "
                        "(input.space) and report.md")
    p.add_argument("--noise-um", type=positive, default=None, metavar="UM",
                   help="noise sd of one measured deflection in µm, if known (default: "
                        "estimated from replicate curves, or from the curves' differences)")
    p.add_argument("--alpha", type=_level, default=d.alpha,
                   help=f"level of the systematic-misfit test (default {d.alpha:g})")
    p.add_argument("--delta-bic", type=_negative, default=d.delta_bic, metavar="DB",
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
    p.add_argument("--repeats", type=positive_int, default=d.repeats,
                   help=f"window focusing runs per fit (default {d.repeats})")
    p.add_argument("--seed", type=non_negative_int, default=d.seed,
                   help="random seed, >= 0; the same seed gives the same report (default 0)")
    p.add_argument("--level", type=_level, default=d.level,
                   help="confidence level of the profile-likelihood intervals of every fit "
                        f"(default {d.level:g})")
    p.add_argument("--no-holdout", action="store_true",
                   help="skip the cross-probe holdout (faster)")
    add_geometry_arguments(p)


def command(args: argparse.Namespace) -> int:
    """Run ``skinsuction diagnose``; returns the exit code (0)."""
    from skinsuction.errors import InputError

    from ._diagnose import diagnose_file
    from skinsuction.space import SpaceFileError, SpaceMissingError
    from ._report import write_report

    settings = Settings(alpha=args.alpha, delta_bic=args.delta_bic, noise_um=args.noise_um,
                        model_error_um=args.model_error_um, repeats=args.repeats,
                        seed=args.seed, holdout=not args.no_holdout,
                        level=args.level, pattern_gate=args.pattern_gate)
    from skinsuction.measured import is_time_curve_file

    if is_time_curve_file(args.measured):
        return _time_command(args, settings)
    try:
        report = diagnose_file(args.measured, args.space_dir, settings,
                               thickness=thickness_from_args(args),
                               on_demand=False if args.no_solve else None,
                               workers=args.workers)
    except (SpaceMissingError, SpaceFileError) as err:
        raise InputError(str(err)) from None
    try:
        paths = write_report(report, args.out)
    except OSError as err:
        raise InputError(f"{args.out}: cannot write ({err.strerror or err})") from None
    space = (report.get("input") or {}).get("space") or {}
    if space.get("description"):
        print(f"space: {space['description']}")
    print(report["summary"])
    print(f"baseline: {report['baseline']['description']}")
    print(f"wrote {', '.join(str(p) for p in paths.values())}")
    sys.stdout.flush()
    return 0


def _time_command(args, settings) -> int:
    """``skinsuction diagnose`` of a time-curve file: is it creep?"""
    from skinsuction.errors import InputError
    from skinsuction.space import SpaceFileError, SpaceMissingError

    from ._time import diagnose_time_file, write_time_report

    try:
        report = diagnose_time_file(args.measured, args.space_dir, settings,
                                    thickness=thickness_from_args(args),
                                    solve_on_demand=not args.no_solve, workers=args.workers)
    except (SpaceMissingError, SpaceFileError) as err:
        raise InputError(str(err)) from None
    try:
        paths = write_time_report(report, args.out)
    except OSError as err:
        raise InputError(f"{args.out}: cannot write ({err.strerror or err})") from None
    for w in report["warnings"]:
        print(f"warning: {w}", file=sys.stderr)
    print(report["summary"])
    print(f"wrote {', '.join(str(p) for p in paths.values())}")
    sys.stdout.flush()
    return 0
