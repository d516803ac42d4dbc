"""``skinsuction design``: which probes and suction will answer the study's question.

::

    skinsuction design --out DIR [--skins curves.parquet | --x1d 0.007 0.09 ...] \\
        [--probes 2 6 2+6 4+8] [--suction 100 300 500] [--precision X1h=0.2] \\
        [--tell pre_tension hypodermis_thickness] [--given t_d=0.1] \\
        [--protocols ramp mode1 mode2] [--mode1 3,3,2] [--mode2-rate 25]

The work is :func:`skinsuction.design.run_design`; this module only takes the
arguments and prints the recommendation.
"""

from __future__ import annotations

import argparse

from skinsuction._argtypes import positive, positive_int

from ._common import EXIT_OK, CLIError, add_out, add_seed, add_space

__all__ = ["HELP", "DESCRIPTION", "add_arguments", "run"]

HELP = "plan a measurement: the probes and suction that answer a question, before measuring"

DESCRIPTION = (
    "Predict, for a box of plausible skins (or the skins of a study's table) and "
    "candidate designs (probe sets, a ramp's suction or mode 1 and mode 2 time curves, "
    "noise, 0.01 mm resolution, thicknesses given), the 95 % interval of X1d and X1h "
    "(and of the relaxation spectrum's g and tau for time curves; median and 90th "
    "percentile over the skins, the fraction bounded), each cause's detectable "
    "fraction and each pair's attribution ceiling; computed from the simulated "
    "spaces on noise-free curves, no FE run. Recommends the design with the fewest "
    "probes, then the lowest suction, that meets the question, or says that none "
    "does. Writes DIR/design.md, designs.csv, predictions.csv, design.json and "
    "precision.png.")


def _pair(text: str) -> tuple:
    key, sep, value = text.partition("=")
    if not sep:
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE, got {text!r}")
    try:
        v = float(value)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: {value!r} is not a number") from None
    if not v > 0:
        raise argparse.ArgumentTypeError(f"{text!r}: the value must be > 0")
    return key.strip(), v


def _timing(text: str) -> tuple:
    try:
        on, off, cycles = (float(x) for x in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected ON,OFF,CYCLES (e.g. 3,3,2), got {text!r}") \
            from None
    if not (on > 0 and off > 0 and cycles >= 1 and cycles == int(cycles)):
        raise argparse.ArgumentTypeError(f"{text!r}: on and off must be > 0 s, cycles a "
                                         "whole number >= 1")
    return on, off, cycles


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Every argument of ``skinsuction design``.

    Parameters
    ----------
    p : argparse.ArgumentParser

    Returns
    -------
    None
    """
    add_out(p, help="output folder: design.md, designs.csv, predictions.csv, design.json, "
                    "precision.png")
    add_space(p, help="the scale-free simulated space (default: the workflow's build under "
                      "the working directory, else the one shipped with skinsuction)")
    box = p.add_argument_group("the skins (a box drawn log-uniform, or a study's table)")
    box.add_argument("--skins", metavar="TABLE",
                     help="a study's curves.parquet (or a CSV with x1d_mpa, x1h_mpa and "
                          "optionally dermis_thickness_mm, hypodermis_thickness_mm): its "
                          "estimates are the skins")
    box.add_argument("--x1d", nargs=2, type=positive, metavar=("LO", "HI"), default=None,
                     help="X1d range in MPa (default 0.007 0.09: forearm E = 129 ± 88 kPa "
                          "up to the paper's fit)")
    box.add_argument("--ratio", nargs=2, type=positive, metavar=("LO", "HI"), default=None,
                     help="X1h/X1d range (default 0.003 0.3)")
    box.add_argument("--dermis-mm", nargs=2, type=positive, metavar=("LO", "HI"), default=None,
                     help="dermis thickness range in mm (default the paper's 1 mm)")
    box.add_argument("--hypodermis-mm", nargs=2, type=positive, metavar=("LO", "HI"),
                     default=None, help="hypodermis thickness range in mm (default 1 mm)")
    box.add_argument("--g", nargs=2, type=positive, metavar=("LO", "HI"), default=None,
                     help="relaxation fraction g of a one-term spectrum, for mode 1 and "
                          "mode 2 designs (default 0.1 1)")
    box.add_argument("--tau", nargs=2, type=positive, metavar=("LO", "HI"), default=None,
                     help="its relaxation time in s (default 0.1 1)")
    box.add_argument("--n-skins", type=positive_int, default=40,
                     help="skins drawn from the box (default 40)")
    add_seed(p, help="seed of the skins drawn (default 0)")
    d = p.add_argument_group("the candidate designs (every probe set at every suction)")
    d.add_argument("--probes", nargs="+", default=["2", "6", "2+6", "4+8", "2+6+8"],
                   metavar="SET", help="probe sets, e.g. 2 6 2+6 4+8 (default 2 6 2+6 4+8 "
                                       "2+6+8)")
    d.add_argument("--suction", nargs="+", type=positive, default=[100.0, 300.0, 500.0],
                   metavar="MBAR", help="ramp tops, 0 to it in 2 mbar steps (default 100 300 "
                                        "500)")
    d.add_argument("--protocols", nargs="+", choices=["ramp", "mode1", "mode2"],
                   default=["ramp"], help="a quasi-static ramp (default), and/or the "
                   "Cutometer's mode 1 (hold and release at the suction) and mode 2 (up "
                   "and down to it) time curves")
    d.add_argument("--mode1", type=_timing, default=None, metavar="ON,OFF,CYCLES",
                   help="mode 1's timing: seconds on, seconds off, cycles (default 3,3,2)")
    d.add_argument("--mode2-rate", type=positive, default=None, metavar="MBAR_S",
                   help="mode 2's loading rate in mbar/s (default 25)")
    d.add_argument("--sample-hz", type=positive, default=100.0,
                   help="the time curves' sampling rate (default 100 Hz)")
    d.add_argument("--noise-um", type=float, default=2.0,
                   help="noise sd of one deflection in µm (default 2)")
    d.add_argument("--resolution-mm", type=float, default=0.01,
                   help="the device's reading step (default 0.01 mm; 0: none)")
    d.add_argument("--given", nargs="+", type=_pair, default=[], metavar="LAYER=SD",
                   help="thicknesses measured (ultrasound, OCT) with their sd in mm: "
                        "t_d=0.1, t_h=0.2")
    q = p.add_argument_group("the question")
    q.add_argument("--precision", nargs="+", type=_pair, default=[], metavar="PARAM=FRACTION",
                   help="parameters to measure and the largest half-width of their 95 %% "
                        "interval, e.g. X1h=0.2 (±20 %%)")
    q.add_argument("--tell", nargs="+", default=[], metavar="CAUSE",
                   help="causes to tell apart (strain_stiffening, pre_tension, "
                        "hypodermis_thickness, dermis_thickness); one: detect it")
    q.add_argument("--quantile", type=float, default=0.9,
                   help="fraction of skins that must meet each precision (default 0.9)")
    q.add_argument("--rate", type=float, default=0.95,
                   help="attribution ceiling each cause must reach (default 0.95)")
    p.add_argument("--workers", type=positive_int, default=1, help="processes (default 1)")
    p.add_argument("--solve-rays", action="store_true",
                   help="at layers other than 1 mm, solve the causes' rays there (FE; slow) "
                        "instead of carrying their effects over from 1 mm")
    p.add_argument("--no-figure", action="store_true", help="skip precision.png")


def run(args: argparse.Namespace) -> int:
    """Run ``skinsuction design``.

    Parameters
    ----------
    args : argparse.Namespace

    Returns
    -------
    int
        0.
    """
    from skinsuction.design import Box, Question, designs_from, run_design, skins_from_table

    try:
        if args.skins:
            skins, source = skins_from_table(args.skins), str(args.skins)
        else:
            box = Box(**{k: v for k, v in (("x1d_mpa", args.x1d), ("x1h_ratio", args.ratio),
                                           ("t_d_mm", args.dermis_mm),
                                           ("t_h_mm", args.hypodermis_mm), ("g", args.g),
                                           ("tau_s", args.tau)) if v is not None})
            skins = box.draw(args.n_skins, args.seed)
            source = f"{args.n_skins} drawn from the box, seed {args.seed}"
        timing = {k: v for k, v in (("mode1", args.mode1),
                                    ("mode2", args.mode2_rate and (args.mode2_rate,)))
                  if v}
        designs = designs_from(args.probes, args.suction, noise_um=args.noise_um,
                               resolution_mm=args.resolution_mm, given=dict(args.given),
                               protocols=args.protocols, timing=timing,
                               sample_hz=args.sample_hz)
        question = Question(dict(args.precision), tuple(args.tell), args.quantile, args.rate)
    except (ValueError, FileNotFoundError, OSError) as err:
        raise CLIError(str(err)) from None
    try:
        r = run_design(skins, designs, question, args.out, space_dir=args.space,
                       workers=args.workers, solve_rays=args.solve_rays, source=source,
                       seed=args.seed, figures=not args.no_figure)
    except ValueError as err:
        raise CLIError(str(err)) from None
    choice = r["recommendation"]
    print(f"question: {question.text}")
    if choice["met"]:
        print(f"recommended: {choice['design']} ({len(choice['meeting'])} of "
              f"{len(designs)} designs meet it)")
    else:
        print(f"no design meets it; the best offered: {choice['design']}")
    for k, s in choice["criteria"].items():
        print(f"  {k}: {'met' if s <= 0 else 'not met'}")
    for n in r["notes"]:
        print(f"note: {n}")
    print(f"wrote {', '.join(r['paths'].values())}")
    return EXIT_OK
