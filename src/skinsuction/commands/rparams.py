"""``skinsuction rparams``: the standard Cutometer parameters of time curves.

::

    skinsuction rparams TIME_CURVES.csv --out DIR [--ue-time-s 0.1]

Per probe and cycle Ue, Uv, Uf, Ur, Ua (mm) and R0-R9 of a mode-1 curve, the
largest and residual deformation and the hysteresis of a mode-2 curve
(:func:`skinsuction.measured.r_parameters`, :func:`skinsuction.measured.ramp_parameters`).
Writes ``DIR/rparams.csv``, ``DIR/ramp_parameters.csv`` (mode 2) and
``DIR/rparams.json``; prints the tables.
"""

from __future__ import annotations

import argparse
import sys

from skinsuction._argtypes import positive

from ._common import EXIT_OK, CLIError, add_measured, add_out, writing

__all__ = ["HELP", "DESCRIPTION", "add_arguments", "run", "r_heading"]

HELP = "the standard Cutometer parameters (Ue ... Ua, R0-R9) of time curves"

DESCRIPTION = (
    "Read Cutometer time curves (deflection and suction against time), find the "
    "phases of the suction (rise, hold, release, off) and the protocol (mode 1: "
    "cycles at a constant suction; mode 2: a ramp up and down), the deflection's "
    "resolution and noise, and compute per probe and cycle Ue (read --ue-time-s after "
    "the onset), Uv, Uf, Ur, Ua (mm) and R0-R9 (mode 1), or the largest and residual "
    "deformation and the hysteresis (mode 2). Writes DIR/rparams.csv, "
    "DIR/ramp_parameters.csv (mode 2) and DIR/rparams.json; prints the table. Bad "
    "input gives a one-line error naming the file, line and column, exit code 2.")

#: columns printed in mm (3 decimals)
_MM_COLUMNS = {"Ue", "Uv", "Uf", "Ur", "Ua", "R0", "R1", "R3", "R4", "R8", "R9", "Umax",
               "Ures", "Uend"}


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Every argument of ``skinsuction rparams``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser.

    Returns
    -------
    None
    """
    add_measured(p, metavar="FILE",
                 help="time curves: CSV with columns probe_mm (mm), time_s (s), "
                      "pressure_mbar (suction, positive, mbar), deflection_mm (mm, zeroed "
                      "before the first suction) and optionally curve (replicate id); '#' "
                      "lines are comments")
    add_out(p, help="output folder: rparams.csv (one row per probe and cycle of a mode-1 "
                    "curve: Ue, Uv, Uf, Ur, Ua in mm, R0-R9), ramp_parameters.csv (mode-2 "
                    "curves) and rparams.json (options, phases, resolution, noise, "
                    "versions), written atomically")
    p.add_argument("--ue-time-s", type=positive, default=0.1, metavar="S",
                   help="when Ue is read after the suction onset, and the retraction Ur "
                        "after the release onset, in s (default 0.1)")


def run(args: argparse.Namespace) -> int:
    """Run ``skinsuction rparams``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments of :func:`add_arguments`.

    Returns
    -------
    int
        0 (a file with no mode-1 or mode-2 curve raises, exit code 2).
    """
    from skinsuction.measured import load_time_curves

    data = load_time_curves(args.measured)
    rtable, ramp, skipped, has_r = _tables(data, args)
    with writing(args.out):
        written = _write(data, rtable, ramp, args)
    for note in data.notes:
        print(note)
    if has_r:
        print("\n" + r_heading(args.ue_time_s))
        print(_table_text(rtable))
    if ramp is not None:
        print("\nmode 2 (R0-R9 need a hold at constant suction and do not apply):")
        print(_table_text(ramp))
    for c in skipped:
        print(f"{c.label}: {c.protocol}; neither R0-R9 nor ramp parameters apply")
    for w in data.warnings:
        print(f"warning: {w}", file=sys.stderr)
    print(f"wrote {', '.join(str(p) for p in written)}")
    return EXIT_OK


def r_heading(ue_time_s: float) -> str:
    """The line printed above the R-parameter table.

    Parameters
    ----------
    ue_time_s : float
        When Ue and Ur are read, s.

    Returns
    -------
    str
    """
    return (f"R parameters (mm and ratios; Ue read {ue_time_s:g} s after onset, Ur "
            f"{ue_time_s:g} s after release; R3, R4, R9 of the measurement):")


def _tables(data, args):
    """``(R table, ramp table or None, curves of neither protocol, any mode-1 curve)``."""
    import pandas as pd

    from skinsuction.measured import R_COLUMNS, RAMP_COLUMNS, r_parameters, ramp_parameters

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
    ramp = pd.concat(ramp_frames, ignore_index=True)[
        [k for k in RAMP_COLUMNS if named or k != "curve"]] if ramp_frames else None
    return rtable, ramp, skipped, bool(r_frames)


def _write(data, rtable, ramp, args) -> list:
    """Write rparams.csv, ramp_parameters.csv (if any) and rparams.json; their paths."""
    import json
    from pathlib import Path

    from skinsuction import __version__
    from skinsuction._files import atomic_output, file_sha256
    from skinsuction.provenance import collect

    out = Path(args.out)
    written = []
    with atomic_output(out / "rparams.csv") as tmp:
        rtable.to_csv(tmp, index=False, float_format="%.6g")
    written.append(out / "rparams.csv")
    if ramp is not None:
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
    return written


def _table_text(frame) -> str:
    """A table for the terminal: mm with 3 decimals, other numbers with 4 digits."""
    formats = {c: (lambda v: f"{v:.3f}") for c in frame.columns
               if c in _MM_COLUMNS or c.startswith("R")}
    formats.update({c: (lambda v: f"{v:.4g}") for c in ("probe_mm", "p_max_mbar", "rate_mbar_s",
                                                        "hysteresis_mbar_mm",
                                                        "hysteresis_fraction")
                    if c in frame.columns})
    return frame.to_string(index=False, formatters=formats, na_rep="nan")


def _curve_record(c) -> dict:
    """The JSON record of one time curve: protocol, resolution, noise, cycles (s)."""
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
