"""``skinsuction identify``: X1d and X1h of a measured file on a simulated space.

::

    skinsuction identify MEASURED.csv [--space PATH] \\
        --objective single|weighted|ratio [--probe 6] [--alpha 0.5] [--repeats 100] \\
        [--seed 0] --out DIR

The file is read once (:func:`skinsuction.measured.read_measurement`): a pressure
ramp is fitted by window focusing with the chosen objective, time curves jointly
with a Prony spectrum.  Writes ``DIR/identification.json`` and ``DIR/fit.png``,
``DIR/fit.pdf``.
"""

from __future__ import annotations

import argparse
import math
import sys

from skinsuction._argtypes import unit_interval

from ._common import (
    EXIT_OK,
    CLIError,
    add_bottom,
    add_geometry_arguments,
    add_level,
    add_measured,
    add_noise_um,
    add_out,
    add_probe,
    add_repeats,
    add_seed,
    add_space,
    interval_text,
    solve_from_args,
    thickness_from_args,
    writing,
)

__all__ = ["HELP", "DESCRIPTION", "add_arguments", "run"]

HELP = "identify X1d and X1h of a measured curve on a simulated space"

DESCRIPTION = (
    "Identify the dermis and hypodermis moduli (X1d, X1h; neo-Hookean) of a measured "
    "suction test by window focusing on a precomputed simulated space (paper "
    "sections 2.3-2.4, 3.2-3.3), repeated with independent seeds. Writes "
    "DIR/identification.json (median estimate, spread over the repeats, E, "
    "iterations, settings, SHA-256 of the inputs) and DIR/fit.png, DIR/fit.pdf "
    "(measured vs fitted curves with residuals). Bad input gives a one-line error "
    "naming the file, line and column, and exit code 2.")

#: --repeats of a pressure ramp by default (the paper's); time curves take 2 then
RAMP_REPEATS = 100


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Every argument of ``skinsuction identify``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser.

    Returns
    -------
    None
    """
    add_measured(p, help="measured curves: CSV with columns probe_mm (mm), pressure_mbar "
                         "(suction, positive, mbar), deflection_mm (apex deflection, mm) and "
                         "optionally curve (replicate id); '#' lines are comments")
    add_space(p, metavar="PATH",
              help="simulated space: a scale-free space (every X1d and any pressure "
                   "protocol within its reach) or a grid database such as "
                   "results/simulated_space/paper.parquet (the paper's 11 x 11 grid). "
                   "Default: results/simulated_space/scale_free if the workflow has "
                   "built it under the working directory, else the default scale-free "
                   "space shipped with skinsuction; the space used is printed and "
                   "recorded in identification.json (space.source, space.description)")
    p.add_argument("--objective", choices=("single", "weighted", "ratio"), default=None,
                   help="single: one probe (paper eq. 4); weighted: the file's two probes "
                        "(2 and 6 mm, or e.g. 4 and 8), alpha on the smaller (eq. 10); ratio: "
                        "larger / smaller probe's deflections (eqs. 11-12). Required for "
                        "pressure ramps; not used for time curves (every curve is fitted "
                        "jointly, or --probe)")
    add_probe(p, help="probe diameter in mm for --objective single, any of 1-12 mm "
                      "(default 6; Cutometer probes are 2, 4, 6 and 8 mm); for time "
                      "curves, fit only this probe's curves")
    p.add_argument("--terms", type=int, choices=(1, 2), default=1,
                   help="time curves: Prony terms of the relaxation spectrum (default 1)")
    p.add_argument("--effect", metavar="CAUSE", default=None,
                   help="time curves: an elastic effect fitted with the spectrum, e.g. "
                        "strain_stiffening (X2d identified too; `diagnose` chooses the "
                        "effects itself)")
    p.add_argument("--fe-correction", type=int, choices=range(6), default=2, metavar="STEPS",
                   help="time curves: steps of the FE correction of the fit (FE time solves "
                        "at the fit remove the fast path's error; one FE time solve a step "
                        "and curve, 1-15 s of CPU with the curve's length; 0: the fast path "
                        "alone; default 2)")
    p.add_argument("--phases", choices=("all", "on"), default="all",
                   help="time curves: fit every point, with the fast path's model error per "
                        "phase in the likelihood (all, default), or only while the suction "
                        "is on (on)")
    p.add_argument("--alpha", type=unit_interval, default=0.5,
                   help="weight of the 2 mm curve for --objective weighted, "
                        "dimensionless in [0, 1] (default 0.5)")
    add_repeats(p, default=RAMP_REPEATS,
                help="independent window focusing runs; the estimate is their median "
                     "(default 100, as in the paper)")
    add_seed(p, help="random seed, >= 0; the same seed gives the same result (default 0)")
    p.add_argument("--curve", metavar="ID",
                   help="replicate id (column 'curve') when the file holds several curves "
                        "of a probe")
    add_bottom(p, help="bottom condition of the space to use (default fixed)")
    add_noise_um(p, help="noise sd of one measured deflection in µm, for the intervals "
                         "(default: estimated from replicates, else from the curve)")
    add_level(p, default=0.95,
              help="confidence level of the profile-likelihood intervals (default 0.95)")
    add_out(p, help="output folder: identification.json and fit.png / fit.pdf "
                    "(measured vs fitted curves, residuals)")
    add_geometry_arguments(p)


def run(args: argparse.Namespace) -> int:
    """Run ``skinsuction identify``: a pressure ramp or time curves, by the file.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments of :func:`add_arguments`.

    Returns
    -------
    int
        0 (errors raise, and the command line prints them).
    """
    from skinsuction.identify import write_identification
    from skinsuction.identify.measured_fit import identify_measured
    from skinsuction.measured import MeasuredTimeData, read_measurement

    data = read_measurement(args.measured)
    if isinstance(data, MeasuredTimeData):
        return _run_time(args, data)
    if args.objective is None:
        raise CLIError("the following arguments are required: --objective (single, weighted "
                       "or ratio) for a pressure ramp")
    result = identify_measured(
        data, args.space, objective=args.objective,
        probe_mm=6.0 if args.probe is None else args.probe,
        alpha=args.alpha, repeats=args.repeats, seed=args.seed, bottom=args.bottom,
        curve=args.curve, noise_um=args.noise_um, level=args.level,
        thickness=thickness_from_args(args), solve_on_demand=solve_from_args(args),
        workers=args.workers,
    )
    with writing(args.out):
        paths = write_identification(result, args.out)
    _print_ramp(result)
    _print_tail(result, paths)
    return EXIT_OK


def _print_ramp(result) -> None:
    """The estimate, its spread and intervals of a pressure ramp's identification.

    Parameters
    ----------
    result : Identification
        Of :func:`skinsuction.identify.measured_fit.identify_measured`.

    Returns
    -------
    None
    """
    est, spread, e = result.estimate, result.spread, result.E
    unit = "" if e["unit"] == "1" else f" {e['unit']}"
    e_txt = "n/a" if e["at_estimate"] is None or not math.isfinite(e["at_estimate"]) \
        else f"{e['at_estimate']:.3g}{unit}"
    print(f"X1d = {est['x1d_mpa']:.4g} MPa, X1h = {est['x1h_mpa']:.4g} MPa (median of "
          f"{result.settings['repeats']} repeats; interquartile range / median "
          f"{100 * spread['x1d_relative_iqr']:.2g} % and {100 * spread['x1h_relative_iqr']:.2g} %), "
          f"E = {e_txt}, median {result.iterations['median']:g} iterations")
    if result.intervals:
        iv = result.intervals
        print(f"{100 * iv['level']:g} % intervals (profile likelihood, noise "
              f"{result.noise['sd_um']:.2g} µm, {result.noise['method']}): "
              f"X1d {interval_text(iv['X1d'])} MPa, X1h {interval_text(iv['X1h'])} MPa")


def _print_tail(result, paths: dict) -> None:
    """Warnings (standard error), the space used and the files written.

    Parameters
    ----------
    result : Identification or TimeIdentification
        The result written.
    paths : dict
        The files of :func:`skinsuction.identify.write_identification`.

    Returns
    -------
    None
    """
    for w in result.warnings:
        print(f"warning: {w}", file=sys.stderr)
    print(f"space: {result.space.get('description') or result.space.get('path')}")
    print(f"wrote {paths['json']}, {paths['png']}, {paths['pdf']}")


def _run_time(args: argparse.Namespace, data) -> int:
    """``identify`` of time curves: X1d, X1h (long-time) and a Prony spectrum.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments of :func:`add_arguments`.
    data : MeasuredTimeData
        The file's time curves, as read.

    Returns
    -------
    int
        0.
    """
    from skinsuction.identify import write_identification
    from skinsuction.identify.time_curves import identify_time_file

    if args.objective is not None:
        print("note: --objective is for pressure ramps; the time curves are fitted jointly",
              file=sys.stderr)
    repeats = 2 if args.repeats == RAMP_REPEATS else args.repeats
    result = identify_time_file(
        data, args.space, terms=args.terms,
        probes=None if args.probe is None else [args.probe], curve=args.curve,
        repeats=repeats, seed=args.seed, noise_um=args.noise_um, level=args.level,
        phases=args.phases, thickness=thickness_from_args(args),
        solve_on_demand=solve_from_args(args), workers=args.workers, effect=args.effect,
        fe_correction=args.fe_correction)
    with writing(args.out):
        paths = write_identification(result, args.out)
    _print_time(result)
    _print_tail(result, paths)
    return EXIT_OK


def _print_time(result) -> None:
    """The moduli, the spectrum, the fit per curve and the R parameters of time curves.

    Parameters
    ----------
    result : TimeIdentification
        Of :func:`skinsuction.identify.time_curves.identify_time_file`.

    Returns
    -------
    None
    """
    iv = result.intervals
    spectrum = ", ".join(f"g_{k} = {g:.3g} {interval_text(iv[f'g_{k}'])}, tau_{k} = {t:.3g} s "
                         f"{interval_text(iv[f'tau_{k}'])}"
                         for k, (g, t) in enumerate(zip(result.g, result.tau_s), 1))
    print(f"X1d = {result.X1d:.4g} MPa {interval_text(iv['X1d'])}, X1h = "
          f"{result.X1h:.4g} MPa {interval_text(iv['X1h'])} (long-time; "
          f"{100 * iv['level']:g} % intervals, {iv['method'].split(' in ')[0]})")
    effect = result.model.get("effect")
    if effect is not None:
        symbol = next(k for k in result.model if k not in ("name", "convention", "terms",
                                                          "effect"))
        print(f"{effect}: {symbol} = {result.model[symbol]:.4g} {interval_text(iv[symbol])}")
    print(f"spectrum: {spectrum}; instantaneous X1d = {result.X1d_instantaneous:.4g} MPa, "
          f"X1h = {result.X1h_instantaneous:.4g} MPa")
    for c in result.fit_quality["curves"]:
        parts = ", ".join(f"{ph} {v['rms_um']:.2g} µm" for ph, v in c["phases"].items()
                          if v["rms_um"] is not None)
        print(f"{c['curve']} ({c['protocol']}): reduced chi2 {c['chi2'] / max(c['points'], 1):.3g}"
              f"; RMS residual per phase: {parts}")
    rows = result.r_parameters["mode1"]
    if rows:
        r = rows[0]
        print(f"R parameters, first cycle: Ue {r['Ue']:.2f}, Uf {r['Uf']:.2f} mm, R2 "
              f"{r['R2']:.2f}, R5 {r['R5']:.2f}, R6 {r['R6']:.2f}, R7 {r['R7']:.2f} "
              f"({len(rows)} rows in identification.json)")
    for r in result.r_parameters["mode2"][:1]:
        print(f"ramp parameters: Umax {r['Umax']:.2f} mm, Ures {r['Ures']:.2f} mm, "
              f"hysteresis {100 * r['hysteresis_fraction']:.2g} %")
