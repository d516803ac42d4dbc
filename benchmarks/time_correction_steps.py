"""The FE correction's time solves: graded steps against a step at every sample.

    python benchmarks/time_correction_steps.py [--rate-hz 100] [--try FIRST GROWTH LARGEST]

Every mode-1 fit is corrected by FE time solves at the fit
(:func:`skinsuction.identify.fe_corrected_fit`, two per curve by default). A
Cutometer samples at 100 Hz: a step at every sample is 1 000 steps for 10 s. The
suction is linear between the breaks of its slope, so steps graded from each
break (2 ms, doubling, at most 0.2 s; before 7 December 2026 1 ms growing by 1.5
to 0.15 s) follow the same load path; the samples are then read by PCHIP between
breaks. For skins of the layers study and the published face values (creep with
and without stiffening; 2 and 8 mm probes; mode 1, 3 s on / 2 s off, 2 cycles),
prints the steps, the CPU of each solve and the largest difference at the
samples, for both gradings (and a grading to try, ``--try``). Asserts nothing.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

SKINS = {  # name: (X1d, X1h, X2d MPa, g, tau s, probe mm, suction mbar)
    "face, creep + stiffening": (0.018, 3e-4, 0.1, [0.5, 1.5], [0.05, 2.5], 2.0, 450.0),
    "forearm, creep": (0.03, 1e-3, 0.0, [0.8], [0.3], 2.0, 150.0),
    "8 mm, strong creep + stiffening": (0.046, 1.15e-3, 0.367, [0.73], [0.76], 8.0, 400.0),
}

#: The grading before 7 December 2026: (first step s, growth, largest step s).
PREVIOUS_GRADING = (1e-3, 1.5, 0.15)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rate-hz", type=float, default=100.0)
    ap.add_argument("--try", dest="trial", type=float, nargs=3, default=None,
                    metavar=("FIRST_S", "GROWTH", "LARGEST_S"), help="a grading to try too")
    args = ap.parse_args(argv)

    from skinsuction.evaluation import mode1_suction, virtual_skin_curve, write_time_csv
    from skinsuction.identify._time_correction import (
        FIRST_STEP_S,
        GRADED_STEPS_S,
        MAX_STEP_S,
        STEP_GROWTH,
        fe_time_curve,
        solve_times,
    )
    from skinsuction.identify.time_curves import prepare_time_fit
    from skinsuction.measured import load_time_curves
    from skinsuction.model import Skin
    from skinsuction.space import load_space
    from skinsuction.viscoelastic import Prony

    import skinsuction.viscoelastic as ve

    solve, newton = ve.simulate_history, []

    def counted(*args, **kwargs):  # the Newton iterations of each solve
        h = solve(*args, **kwargs)
        newton.append(h.newton_iterations)
        return h

    ve.simulate_history = counted
    space = load_space()
    print(f"mode 1, 3 s on / 2 s off, 2 cycles, {args.rate_hz:g} Hz; reference mesh")
    gradings = {"graded": (FIRST_STEP_S, STEP_GROWTH, MAX_STEP_S),
                "before": PREVIOUS_GRADING}
    if args.trial:
        gradings["tried"] = tuple(args.trial)
        print(f"tried: first step {args.trial[0]:g} s, growth {args.trial[1]:g}, "
              f"largest {args.trial[2]:g} s")
    names = " / ".join(gradings)
    print(f"| skin | probe | steps: samples / {names} | Newton iterations | CPU-s | "
          f"max |graded - samples| (µm): {names} | Uf (µm) |")
    print("|---|---|---|---|---|---|---|")
    for name, (x1d, x1h, x2d, g, tau, probe, level) in SKINS.items():
        skin = Skin.two_layer(x1d, x1h, x2d=x2d, spectrum=Prony(g, tau))
        t, p, _, exact, _ = virtual_skin_curve(skin, mode1_suction(level), probe_mm=probe,
                                               rate_hz=args.rate_hz, noise_mm=0.0,
                                               resolution_mm=0.0)
        with tempfile.TemporaryDirectory() as tmp:
            path = write_time_csv(Path(tmp) / "c.csv", [(probe, t, p, exact)], [name])
            d = prepare_time_fit(load_time_curves(path), space, noise_um=3.0)["data"][0]
        newton.clear()
        c0 = time.process_time()
        ref = fe_time_curve(skin, d, steps="samples")
        cpu, n, diff = [time.process_time() - c0], [], []
        for grading in gradings.values():
            c0 = time.process_time()
            m = fe_time_curve(skin, d, steps="graded", grading=grading)
            cpu.append(time.process_time() - c0)
            n.append(solve_times(d.time_s, d.breaks, grading).size)
            diff.append(1e3 * np.abs(m - ref).max())
        fine = (d.time_s[d.breaks][:, None] + GRADED_STEPS_S[None, :]).ravel()
        n_samples = np.unique(np.round(np.concatenate(
            [d.time_s, fine[fine < d.time_s[-1]]]), 9)).size
        print(f"| {name} | {probe:g} mm | {n_samples} / {' / '.join(map(str, n))} | "
              f"{' / '.join(map(str, newton))} | "
              f"{' / '.join(f'{c:.1f}' for c in cpu)} | "
              f"{' / '.join(f'{x:.3f}' for x in diff)} | {1e3 * ref.max():.0f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
