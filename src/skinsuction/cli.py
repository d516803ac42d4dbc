"""The ``skinsuction`` command: ``simulate`` a suction test, ``identify`` moduli,
``diagnose`` the misfit of the neo-Hookean model, run a whole ``study``.

::

    skinsuction simulate --probe 6 --x1d 0.08 --x1h 4.1e-4 [--out curve.csv]
    skinsuction identify MEASURED.csv [--space PATH] \\
        --objective single|weighted|ratio [--probe 6] [--alpha 0.5] [--repeats 100] \\
        [--seed 0] --out DIR
    skinsuction diagnose MEASURED.csv --out DIR
    skinsuction study FOLDER_OR_LONG.csv --out DIR [--no-diagnose] [--workers 2]
    skinsuction rparams TIME_CURVES.csv --out DIR [--ue-time-s 0.1]

Each subcommand is a :class:`Command` in :data:`COMMANDS`: a function that adds
its arguments to an ``argparse`` parser and a function that runs it and returns
the exit code.  A new subcommand is one more entry.

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
import math
import sys
from dataclasses import dataclass
from typing import Callable

from skinsuction._argtypes import (
    non_negative,
    non_negative_int,
    positive,
    positive_int,
    refinement,
    unit_interval,
)

__all__ = ["main", "build_parser", "COMMANDS", "Command", "CLIError"]

EXIT_OK, EXIT_INTERNAL, EXIT_INPUT, EXIT_NOT_CONVERGED, EXIT_INTERRUPTED = 0, 1, 2, 3, 130


class CLIError(Exception):
    """A user-facing error: printed as one line, exits with ``code``."""

    def __init__(self, message: str, code: int = EXIT_INPUT):
        super().__init__(" ".join(str(message).split()))
        self.code = code


@dataclass(frozen=True)
class Command:
    """A subcommand: its help, how it adds its arguments, how it runs."""

    name: str
    help: str
    description: str
    add_arguments: Callable[[argparse.ArgumentParser], None]
    run: Callable[[argparse.Namespace], int]


def interval_text(iv: dict) -> str:
    """``[lo, hi]`` of an interval of a JSON result (see ``Interval.text``)."""
    from skinsuction.identify import Interval

    return Interval(iv["estimate"], iv["lower"], iv["upper"], iv["lower_open"],
                    iv["upper_open"]).text()


def _fmt(x) -> str:
    x = float(x)
    return "nan" if math.isnan(x) else f"{x:.10g}"


# ------------------------------------------------------------------ simulate
def _simulate_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--probe", type=positive, required=True, metavar="MM",
                   help="aperture (probe) diameter in mm, e.g. 6 or 2")
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
    p.add_argument("--bottom", choices=("fixed", "axial", "free"), default="fixed",
                   help="hypodermis/bone interface: fixed = restrained laterally and axially, "
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
    p.add_argument("--out", metavar="FILE",
                   help="write the CSV to FILE (atomically) instead of standard output")


def _curve_csv(curve, args) -> str:
    from skinsuction import __version__

    lines = [
        f"# skinsuction simulate {__version__}: apex deflection M(p) of the suction test",
        f"# probe_mm: {_fmt(args.probe)}",
        f"# x1d_mpa: {_fmt(args.x1d)}",
        f"# x1h_mpa: {_fmt(args.x1h)}",
        f"# x2d_mpa: {_fmt(args.x2d)}",
        f"# x2h_mpa: {_fmt(args.x2h)}",
        f"# t_d_mm: {_fmt(args.td)}",
        f"# t_h_mm: {_fmt(args.th)}",
        f"# bottom: {args.bottom}",
        f"# refinement: {_fmt(args.refinement)}",
        f"# converged: {'true' if curve.converged else 'false'}",
        f"# last_converged_mbar: {_fmt(curve.last_converged_mbar)}",
        f"# reason: {' '.join(str(curve.reason or '').split())}",
        f"# newton_iterations: {int(curve.newton_iterations or 0)}",
        f"# dofs: {int(curve.dofs or 0)}",
        f"# seconds: {float(curve.seconds or 0.0):.3f}",
    ]
    rows = zip(curve.pressure_mbar, curve.deflection_mm)
    if getattr(args, "measured_format", False):
        # a measured file has no NaN rows: the curve stops where the solver stopped
        lines.append("probe_mm,pressure_mbar,deflection_mm")
        lines += [f"{_fmt(args.probe)},{_fmt(p)},{_fmt(m)}" for p, m in rows if m == m]
    else:
        lines.append("pressure_mbar,deflection_mm")
        lines += [f"{_fmt(p)},{_fmt(m)}" for p, m in rows]
    return "\n".join(lines) + "\n"


#: seconds before `simulate` shows its progress (a default-mesh curve takes about 1 s)
PROGRESS_QUIET_S = 2.0


def _run_simulate(args: argparse.Namespace) -> int:
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
    text = _curve_csv(curve, args)
    if args.out:
        from skinsuction._files import atomic_output

        try:
            with atomic_output(args.out) as tmp:
                tmp.write_text(text, encoding="utf-8")
        except OSError as err:
            raise CLIError(f"{args.out}: cannot write ({err.strerror or err})") from None
    else:
        sys.stdout.write(text)
        sys.stdout.flush()
    if not curve.converged:
        print(f"skinsuction simulate: warning: the solver stopped at "
              f"{_fmt(curve.last_converged_mbar)} mbar ({curve.reason}); "
              "the curve is NaN beyond", file=sys.stderr)
        return EXIT_NOT_CONVERGED
    return EXIT_OK


# ------------------------------------------------------------------ identify
def _identify_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("measured", metavar="MEASURED.csv",
                   help="measured curves: CSV with columns probe_mm (mm), pressure_mbar "
                        "(suction, positive, mbar), deflection_mm (apex deflection, mm) and "
                        "optionally curve (replicate id); '#' lines are comments")
    p.add_argument("--space", default=None, metavar="PATH",
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
    p.add_argument("--probe", type=positive, default=None, metavar="MM",
                   help="probe diameter in mm for --objective single, any of 1-12 mm "
                        "(default 6; Cutometer probes are 2, 4, 6 and 8 mm); for time "
                        "curves, fit only this probe's curves")
    p.add_argument("--terms", type=int, choices=(1, 2), default=1,
                   help="time curves: Prony terms of the relaxation spectrum (default 1)")
    p.add_argument("--phases", choices=("all", "on"), default="all",
                   help="time curves: fit every point, with the fast path's model error per "
                        "phase in the likelihood (all, default), or only while the suction "
                        "is on (on)")
    p.add_argument("--alpha", type=unit_interval, default=0.5,
                   help="weight of the 2 mm curve for --objective weighted, "
                        "dimensionless in [0, 1] (default 0.5)")
    p.add_argument("--repeats", type=positive_int, default=100,
                   help="independent window focusing runs; the estimate is their median "
                        "(default 100, as in the paper)")
    p.add_argument("--seed", type=non_negative_int, default=0,
                   help="random seed, >= 0; the same seed gives the same result (default 0)")
    p.add_argument("--curve", metavar="ID",
                   help="replicate id (column 'curve') when the file holds several curves "
                        "of a probe")
    p.add_argument("--bottom", choices=("fixed", "axial", "free"), default="fixed",
                   help="bottom condition of the space to use (default fixed)")
    p.add_argument("--noise-um", type=positive, default=None, metavar="UM",
                   help="noise sd of one measured deflection in µm, for the intervals "
                        "(default: estimated from replicates, else from the curve)")
    p.add_argument("--level", type=unit_interval, default=0.95,
                   help="confidence level of the profile-likelihood intervals (default 0.95)")
    p.add_argument("--out", required=True, metavar="DIR",
                   help="output folder: identification.json and fit.png / fit.pdf "
                        "(measured vs fitted curves, residuals)")
    from skinsuction.measured._geometry import add_geometry_arguments

    add_geometry_arguments(p)


def _run_identify(args: argparse.Namespace) -> int:
    from skinsuction.identify.measured_fit import identify_measured, write_identification
    from skinsuction.measured import is_time_curve_file
    from skinsuction.measured._geometry import thickness_from_args

    if is_time_curve_file(args.measured):
        return _run_identify_time(args)
    if args.objective is None:
        raise CLIError("the following arguments are required: --objective (single, weighted "
                       "or ratio) for a pressure ramp")
    result = identify_measured(
        args.measured, args.space, objective=args.objective,
        probe_mm=6.0 if args.probe is None else args.probe,
        alpha=args.alpha, repeats=args.repeats, seed=args.seed, bottom=args.bottom,
        curve=args.curve, noise_um=args.noise_um, level=args.level,
        thickness=thickness_from_args(args), solve_on_demand=not args.no_solve,
        workers=args.workers,
    )
    try:
        paths = write_identification(result, args.out)
    except OSError as err:
        raise CLIError(f"{args.out}: cannot write ({err.strerror or err})") from None
    est, spread, e = result["estimate"], result["spread"], result["E"]
    unit = "" if e["unit"] == "1" else f" {e['unit']}"
    e_txt = "n/a" if e["at_estimate"] is None or not math.isfinite(e["at_estimate"]) \
        else f"{e['at_estimate']:.3g}{unit}"
    print(f"X1d = {est['x1d_mpa']:.4g} MPa, X1h = {est['x1h_mpa']:.4g} MPa (median of "
          f"{result['settings']['repeats']} repeats; interquartile range / median "
          f"{100 * spread['x1d_relative_iqr']:.2g} % and {100 * spread['x1h_relative_iqr']:.2g} %), "
          f"E = {e_txt}, median {result['iterations']['median']:g} iterations")
    if result["intervals"]:
        iv = result["intervals"]
        print(f"{100 * iv['level']:g} % intervals (profile likelihood, noise "
              f"{result['noise']['sd_um']:.2g} µm, {result['noise']['method']}): "
              f"X1d {interval_text(iv['X1d'])} MPa, X1h {interval_text(iv['X1h'])} MPa")
    for w in result["warnings"]:
        print(f"warning: {w}", file=sys.stderr)
    print(f"space: {result['space'].get('description') or result['space'].get('path')}")
    print(f"wrote {paths['json']}, {paths['png']}, {paths['pdf']}")
    return EXIT_OK


def _run_identify_time(args: argparse.Namespace) -> int:
    """``identify`` on a time-curve file: X1d, X1h (long-time) and a Prony spectrum."""
    from skinsuction.identify.time_curves import identify_time_file, write_time_identification
    from skinsuction.measured._geometry import thickness_from_args

    if args.objective is not None:
        print("note: --objective is for pressure ramps; the time curves are fitted jointly",
              file=sys.stderr)
    repeats = 2 if args.repeats == 100 else args.repeats  # 100 is the ramp's default
    result = identify_time_file(
        args.measured, args.space, terms=args.terms,
        probes=None if args.probe is None else [args.probe], curve=args.curve,
        repeats=repeats, seed=args.seed, noise_um=args.noise_um, level=args.level,
        phases=args.phases, thickness=thickness_from_args(args),
        solve_on_demand=not args.no_solve, workers=args.workers)
    try:
        paths = write_time_identification(result, args.out)
    except OSError as err:
        raise CLIError(f"{args.out}: cannot write ({err.strerror or err})") from None
    iv = result["intervals"]
    spectrum = ", ".join(f"g_{k} = {g:.3g} {interval_text(iv[f'g_{k}'])}, tau_{k} = {t:.3g} s "
                         f"{interval_text(iv[f'tau_{k}'])}"
                         for k, (g, t) in enumerate(zip(result["g"], result["tau_s"]), 1))
    q = result["fit_quality"]
    print(f"X1d = {result['X1d']:.4g} MPa {interval_text(iv['X1d'])}, X1h = "
          f"{result['X1h']:.4g} MPa {interval_text(iv['X1h'])} (long-time; "
          f"{100 * iv['level']:g} % intervals, {iv['method'].split(' in ')[0]})")
    print(f"spectrum: {spectrum}; instantaneous X1d = {result['X1d_instantaneous']:.4g} MPa, "
          f"X1h = {result['X1h_instantaneous']:.4g} MPa")
    for c in q["curves"]:
        parts = ", ".join(f"{ph} {v['rms_um']:.2g} µm" for ph, v in c["phases"].items()
                          if v["rms_um"] is not None)
        print(f"{c['curve']} ({c['protocol']}): reduced chi2 {c['chi2'] / max(c['points'], 1):.3g}"
              f"; RMS residual per phase: {parts}")
    rows = result["r_parameters"]["mode1"]
    if rows:
        r = rows[0]
        print(f"R parameters, first cycle: Ue {r['Ue']:.2f}, Uf {r['Uf']:.2f} mm, R2 "
              f"{r['R2']:.2f}, R5 {r['R5']:.2f}, R6 {r['R6']:.2f}, R7 {r['R7']:.2f} "
              f"({len(rows)} rows in identification.json)")
    for r in result["r_parameters"]["mode2"][:1]:
        print(f"ramp parameters: Umax {r['Umax']:.2f} mm, Ures {r['Ures']:.2f} mm, "
              f"hysteresis {100 * r['hysteresis_fraction']:.2g} %")
    for w in result["warnings"]:
        print(f"warning: {w}", file=sys.stderr)
    print(f"space: {result['space'].get('description') or result['space'].get('path')}")
    print(f"wrote {paths['json']}, {paths['png']}, {paths['pdf']}")
    return EXIT_OK


# ------------------------------------------------------------------ diagnose
def _diagnose_arguments(p: argparse.ArgumentParser) -> None:
    from skinsuction.diagnose._cli import add_arguments

    add_arguments(p)


def _run_diagnose(args: argparse.Namespace) -> int:
    from skinsuction.diagnose._cli import command

    return command(args)


# ------------------------------------------------------------------ study
def _study_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("path", metavar="PATH",
                   help="a folder of measured CSVs (ids from '# key: value' lines and an "
                        "optional manifest.csv/.yaml) or one long CSV whose extra columns "
                        "(subject, site, visit, group, ...) are ids")
    p.add_argument("--out", required=True, metavar="DIR",
                   help="output folder: curves.parquet, comparison.csv, summary.md, "
                        "study.json and figures")
    p.add_argument("--space", default=None, metavar="DIR",
                   help="the scale-free simulated space. Default: "
                        "results/simulated_space/scale_free if the workflow has built it "
                        "under the working directory, else the default space shipped with "
                        "skinsuction; the space used is printed and recorded in study.json "
                        "and summary.md")
    p.add_argument("--no-diagnose", action="store_true",
                   help="identify only (much faster: no diagnosis of each curve)")
    p.add_argument("--repeats", type=positive_int, default=2,
                   help="window focusing runs per identification, polished (default 2)")
    p.add_argument("--seed", type=non_negative_int, default=0,
                   help="seed of the study; measurement i uses seed + i (default 0)")
    p.add_argument("--level", type=unit_interval, default=0.95,
                   help="confidence level of the intervals (default 0.95)")
    p.add_argument("--workers", type=positive_int, default=1,
                   help="processes (default 1)")
    p.add_argument("--reports", action="store_true",
                   help="also write each measurement's identification and diagnosis files "
                        "(off by default: thousands of folders for big studies)")


def _run_study(args: argparse.Namespace) -> int:
    from skinsuction.cohort import run_study

    try:
        r = run_study(args.path, args.out, space_dir=args.space, diagnose=not args.no_diagnose,
                      repeats=args.repeats, seed=args.seed, level=args.level,
                      workers=args.workers, reports=args.reports)
    except FileNotFoundError as err:
        raise CLIError(str(err)) from None
    print(f"space: {r['space']}")
    print(f"{r['measurements']} measurements, {r['errors']} with an error, "
          f"{r['seconds']:.1f} s")
    for c in r["comparison"]:
        if c.get("p_value") is None:
            continue
        print(f"{c['group']} ({c.get('comparison', '')}): median change "
              f"{c['median_change_percent']:+.1f} % "
              + (f"[{c['ci_low_percent']:+.1f}, {c['ci_high_percent']:+.1f}] "
                 if c.get("ci_low_percent") is not None else "")
              + f"p = {c['p_value']:.2g}, {c['test']}")
    print(f"wrote {', '.join(r['paths'].values())}")
    return EXIT_OK


# ------------------------------------------------------------------ rparams
def _rparams_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("measured", metavar="FILE",
                   help="time curves: CSV with columns probe_mm (mm), time_s (s), "
                        "pressure_mbar (suction, positive, mbar), deflection_mm (mm, zeroed "
                        "before the first suction) and optionally curve (replicate id); '#' "
                        "lines are comments")
    p.add_argument("--out", required=True, metavar="DIR",
                   help="output folder: rparams.csv (one row per probe and cycle of a mode-1 "
                        "curve: Ue, Uv, Uf, Ur, Ua in mm, R0-R9), ramp_parameters.csv (mode-2 "
                        "curves) and rparams.json (options, phases, resolution, noise, "
                        "versions), written atomically")
    p.add_argument("--ue-time-s", type=positive, default=0.1, metavar="S",
                   help="when Ue is read after the suction onset, and the retraction Ur "
                        "after the release onset, in s (default 0.1)")


def _table_text(frame) -> str:
    mm = {"Ue", "Uv", "Uf", "Ur", "Ua", "R0", "R1", "R3", "R4", "R8", "R9", "Umax", "Ures",
          "Uend"}
    fmt = {c: (lambda v: f"{v:.3f}") for c in frame.columns if c in mm or c.startswith("R")}
    fmt.update({c: (lambda v: f"{v:.4g}") for c in ("probe_mm", "p_max_mbar", "rate_mbar_s",
                                                    "hysteresis_mbar_mm",
                                                    "hysteresis_fraction")
                if c in frame.columns})
    return frame.to_string(index=False, formatters=fmt, na_rep="nan")


def _run_rparams(args: argparse.Namespace) -> int:
    import json
    from pathlib import Path

    import pandas as pd

    from skinsuction import __version__
    from skinsuction._files import atomic_output, file_sha256
    from skinsuction.measured import (
        R_COLUMNS,
        RAMP_COLUMNS,
        load_time_curves,
        r_parameters,
        ramp_parameters,
    )
    from skinsuction.provenance import collect

    data = load_time_curves(args.measured)
    r_frames, ramp_frames, skipped = [], [], []
    for c in data.curves:
        try:
            if c.protocol == "mode 1":
                r_frames.append(r_parameters(c, ue_time_s=args.ue_time_s))
            elif c.protocol == "mode 2":
                ramp_frames.append(ramp_parameters(c))
            else:
                skipped.append(c)
        except ValueError as err:
            raise CLIError(f"{args.measured}: {err}") from None
    if not r_frames and not ramp_frames:
        raise CLIError(f"{args.measured}: no curve is mode 1 (cycles at a constant suction) or "
                       "mode 2 (a ramp up and down): "
                       + "; ".join(n for n in data.notes if "protocol" in n))
    # a curve column only when the file names its curves
    named = any(c.curve for c in data.curves)
    keep = [k for k in R_COLUMNS if named or k != "curve"]
    rtable = pd.concat(r_frames, ignore_index=True)[keep] if r_frames else \
        pd.DataFrame(columns=keep)
    out = Path(args.out)
    written = []
    try:
        with atomic_output(out / "rparams.csv") as tmp:
            rtable.to_csv(tmp, index=False, float_format="%.6g")
        written.append(out / "rparams.csv")
        if ramp_frames:
            ramp = pd.concat(ramp_frames, ignore_index=True)[
                [k for k in RAMP_COLUMNS if named or k != "curve"]]
            with atomic_output(out / "ramp_parameters.csv") as tmp:
                ramp.to_csv(tmp, index=False, float_format="%.6g")
            written.append(out / "ramp_parameters.csv")
        record = {
            "command": "rparams",
            "settings": {"ue_time_s": args.ue_time_s},
            "input": {"path": str(args.measured), "sha256": file_sha256(args.measured)},
            "skinsuction_version": __version__,
            "curves": [_curve_record(c) for c in data.curves],
            "metadata": data.metadata,
            "notes": list(data.notes),
            "warnings": list(data.warnings),
            "files": [p.name for p in written] + ["rparams.json"],
            "provenance": collect(config={"ue_time_s": args.ue_time_s}),
        }
        with atomic_output(out / "rparams.json") as tmp:
            tmp.write_text(json.dumps(record, indent=2) + "\n", encoding="utf-8")
        written.append(out / "rparams.json")
    except OSError as err:
        raise CLIError(f"{args.out}: cannot write ({err.strerror or err})") from None
    for note in data.notes:
        print(note)
    if r_frames:
        print(f"\nR parameters (mm and ratios; Ue read {args.ue_time_s:g} s after onset, Ur "
              f"{args.ue_time_s:g} s after release; R3, R4, R9 of the measurement):")
        print(_table_text(rtable))
    if ramp_frames:
        print("\nmode 2 (R0-R9 need a hold at constant suction and do not apply):")
        print(_table_text(ramp))
    for c in skipped:
        print(f"{c.label}: {c.protocol}; neither R0-R9 nor ramp parameters apply")
    for w in data.warnings:
        print(f"warning: {w}", file=sys.stderr)
    print(f"wrote {', '.join(str(p) for p in written)}")
    return EXIT_OK


def _curve_record(c) -> dict:
    t = c.time_s

    def at(k):
        return None if k is None or k >= t.size else float(t[k])

    return {
        "probe_mm": c.probe_mm, "curve": c.curve, "protocol": c.protocol,
        "samples": len(c), "resolution_mm": c.resolution_mm, "noise_sd_mm": c.noise_sd_mm,
        "quantisation_sd_mm": c.quantisation_sd_mm,
        "pressure_noise_mbar": c.pressure_noise_mbar, "notes": list(c.notes),
        "cycles": [{"cycle": k.index, "kind": k.kind, "level_mbar": k.level_mbar,
                    "onset_s": at(k.onset), "hold_start_s": at(k.hold_start),
                    "hold_end_s": at(k.hold_end), "release_s": at(k.release),
                    "off_s": at(k.off), "end_s": at(k.end)} for k in c.cycles],
    }


# -------------------------------------------------------------- check-config
def _check_config_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("configfiles", nargs="+", metavar="CONFIG.yaml",
                   help="configuration file(s) as given to snakemake --configfile, in order")
    p.add_argument("--base", default=None, metavar="CONFIG.yaml",
                   help="the workflow's default configuration the files are merged over, as "
                        "Snakemake merges them (default: config/config.yaml if present)")
    p.add_argument("--no-base", action="store_true",
                   help="check the files alone (snakemake --replace-workflow-config)")
    p.add_argument("--schema", default=None, metavar="SCHEMA.yaml",
                   help="JSON schema (YAML) of the workflow "
                        "(default: workflow/schemas/config.schema.yaml)")


def _run_check_config(args: argparse.Namespace) -> int:
    from pathlib import Path

    from skinsuction.config import (
        DEFAULT_CONFIG,
        DEFAULT_SCHEMA,
        check_config,
        merge,
        read_config,
    )

    schema = Path(args.schema) if args.schema else DEFAULT_SCHEMA
    if not schema.is_file():
        raise CLIError(f"{schema}: schema not found (run from the project's root, or give --schema)",
                       EXIT_INPUT)
    base = None if args.no_base else (Path(args.base) if args.base else
                                      (DEFAULT_CONFIG if DEFAULT_CONFIG.is_file() else None))
    given = {}
    for path in args.configfiles:
        given = merge(given, read_config(path))
    if given.get("whole_config", False):
        base = None  # as the workflow: such a file is not merged over the default
    config = merge(read_config(base), given) if base is not None else given
    names = ", ".join(args.configfiles)
    check_config(config, schema, source=names if base is None else f"{names} over {base}")
    print(f"{names}: valid YAML and a valid configuration"
          + (f" (merged over {base})" if base is not None else ""))
    return EXIT_OK


# ------------------------------------------------------------------ registry
COMMANDS = {
    c.name: c
    for c in (
        Command(
            "simulate",
            "FE suction curve M(p) at one parameter point",
            "Run the axisymmetric two-layer FE model of the suction test (pressures 0, 2, "
            "..., 100 mbar) and print the apex deflection curve as CSV "
            "(pressure_mbar,deflection_mm) after '#' comment lines with the settings and "
            "the solver outcome (# converged: true|false, # last_converged_mbar, # reason). "
            "Exit code 0 if every pressure converged, 3 if the solver stopped early "
            "(the curve is still written, NaN beyond the last converged pressure).",
            _simulate_arguments,
            _run_simulate,
        ),
        Command(
            "identify",
            "identify X1d and X1h of a measured curve on a simulated space",
            "Identify the dermis and hypodermis moduli (X1d, X1h; neo-Hookean) of a measured "
            "suction test by window focusing on a precomputed simulated space (paper "
            "sections 2.3-2.4, 3.2-3.3), repeated with independent seeds. Writes "
            "DIR/identification.json (median estimate, spread over the repeats, E, "
            "iterations, settings, SHA-256 of the inputs) and DIR/fit.png, DIR/fit.pdf "
            "(measured vs fitted curves with residuals). Bad input gives a one-line error "
            "naming the file, line and column, and exit code 2.",
            _identify_arguments,
            _run_identify,
        ),
        Command(
            "diagnose",
            "show where the neo-Hookean model misfits measured curves, name the cause",
            "Fit the two-layer neo-Hookean model to measured suction curves (one or both "
            "probes), test the residuals for a systematic misfit against the noise, fit "
            "each candidate extension (strain stiffening, dermis thickness, pre-tension) "
            "on the ray spaces built by the workflow, compare them by E, BIC and a "
            "cross-probe holdout, and name the cause (or none). Writes DIR/report.json, "
            "DIR/report.md and figures.",
            _diagnose_arguments,
            _run_diagnose,
        ),
        Command(
            "study",
            "identify and diagnose every curve of a clinical study, compare the groups",
            "Identify (X1d, X1h with 95 % profile-likelihood intervals) and diagnose every "
            "measurement of a study: a folder of measured CSVs or one long CSV with id "
            "columns (subject, site, visit, group, ...). A bad file becomes a row with its "
            "error. Writes DIR/curves.parquet (one row per measurement), DIR/comparison.csv "
            "and DIR/summary.md (paired Wilcoxon within groups, Mann-Whitney between "
            "groups), DIR/study.json and figures.",
            _study_arguments,
            _run_study,
        ),
        Command(
            "rparams",
            "the standard Cutometer parameters (Ue ... Ua, R0-R9) of time curves",
            "Read Cutometer time curves (deflection and suction against time), find the "
            "phases of the suction (rise, hold, release, off) and the protocol (mode 1: "
            "cycles at a constant suction; mode 2: a ramp up and down), the deflection's "
            "resolution and noise, and compute per probe and cycle Ue (read --ue-time-s after "
            "the onset), Uv, Uf, Ur, Ua (mm) and R0-R9 (mode 1), or the largest and residual "
            "deformation and the hysteresis (mode 2). Writes DIR/rparams.csv, "
            "DIR/ramp_parameters.csv (mode 2) and DIR/rparams.json; prints the table. Bad "
            "input gives a one-line error naming the file, line and column, exit code 2.",
            _rparams_arguments,
            _run_rparams,
        ),
        Command(
            "check-config",
            "check a workflow configuration file before snakemake reads it",
            "Read configuration file(s) as `snakemake --configfile` would, merged over the "
            "default config/config.yaml (or alone with --no-base), and check them against "
            "the workflow's schema. A YAML syntax error names the file, line and column "
            "(Snakemake's own message names neither); a bad value names its key. Exit code "
            "0 if valid, 2 otherwise. The workflow's further checks (a target outside its "
            "space, a figure naming an unknown space) run when snakemake starts.",
            _check_config_arguments,
            _run_check_config,
        ),
    )
}


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand of :data:`COMMANDS`."""
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
    """Run the command line; returns the exit code (see the module docstring)."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exit_:  # --help, --version, usage errors
        return int(exit_.code or 0)
    from skinsuction.errors import InputError
    from skinsuction.measured import MeasuredDataError

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
