"""The viscoelastic fast path against FE time solves (prints figures; asserts nothing).

For a few skins drawn over the literature range (long-time X1d, X1h/X1d, and a
two-term spectrum: tau_1 ~ 10 ms, tau_2 0.1-1 s, one spectrum for both layers),
under a mode-1 history (400 mbar, 3 s on / 2 s off, 2 cycles, 10 ms switches) and
a mode-2 history (0 -> 400 -> 0 mbar at 25 mbar/s): the FE time solve
(:func:`skinsuction.viscoelastic.simulate_history`), the fast path
``M_el(p_eff(t))`` on the long-time elastic curve of the same mesh, and the purely
elastic (long-time) model ``M_el(p(t))``. Errors of both against the FE, per
phase (rise: the first 0.1 s after suction on, or the loading ramp; hold; release:
the first 0.1 s after suction off, or the unloading ramp; off): max and RMS in µm
and in % of Uf (the deflection at the end of the first hold; mode 2: the largest
deflection). With ``--x2-over-x1d LO HI`` each draw also stiffens: X2d = k X1d,
k log-uniform in [LO, HI] (the dermis's strain stiffening of paper eq. 9; the
spectrum relaxes it with the rest). A draw whose long-time elastic curve does not reach 400 mbar on this
mesh is reported and skipped. Also: the FE's own time-step error (steps halved)
on the first draw, and the time of one FE history solve.

    OMP_NUM_THREADS=1 python benchmarks/viscoelastic_fast_path.py [--draws 12] [--refinement 0.5]
        [--branches full|isochoric|whole_tensor] [--x2-over-x1d 1 30] [--probe 6]
        [--x1d 0.06 0.15] [--peak 400]

Writes ``benchmarks/out/viscoelastic_fast_path.csv``.
"""

import argparse
import os
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from skinsuction.model import Probe, Skin, simulate  # noqa: E402
from skinsuction.viscoelastic import (  # noqa: E402
    Prony,
    fast_history,
    mode1_history,
    mode2_history,
    simulate_history,
)

PEAK_MBAR = 400.0
PHASES = ("rise", "hold", "release", "off")


def draw_skins(n, seed, x2_range=None, x1d_range=(0.06, 0.15)):
    rng = np.random.default_rng(seed)
    for _ in range(n):
        k = (float(np.exp(rng.uniform(*np.log(x2_range)))) if x2_range else 0.0)
        yield dict(x2_over_x1d=k,
            x1d=float(np.exp(rng.uniform(*np.log(x1d_range)))),
            ratio=float(np.exp(rng.uniform(np.log(0.01), np.log(0.3)))),
            g=(float(rng.uniform(0.05, 0.4)), float(rng.uniform(0.1, 0.5))),
            tau=(float(rng.uniform(0.005, 0.02)), float(np.exp(rng.uniform(np.log(0.1), np.log(1.0))))),
        )


def errors(model, fe, phase, scale):
    rows = {}
    for name in PHASES:
        mask = phase == name
        if not mask.any():
            continue
        d = (model[mask] - fe[mask]) * 1e3  # µm
        rows[name] = (np.max(np.abs(d)), np.sqrt(np.mean(d**2)),
                      100 * np.max(np.abs(d)) / (scale * 1e3), 100 * np.sqrt(np.mean(d**2)) / (scale * 1e3))
    return rows


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--draws", type=int, default=12)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--refinement", type=float, default=0.5)
    parser.add_argument("--branches", default="full", help="full, isochoric or whole_tensor")
    parser.add_argument("--x2-over-x1d", type=float, nargs=2, default=None,
                        help="draw X2d/X1d log-uniform in this range (default: no stiffening)")
    parser.add_argument("--probe", type=float, default=6.0, help="aperture (mm)")
    parser.add_argument("--x1d", type=float, nargs=2, default=(0.06, 0.15),
                        help="long-time X1d range drawn (MPa, log-uniform)")
    parser.add_argument("--peak", type=float, default=PEAK_MBAR, help="suction (mbar)")
    parser.add_argument("--out", default="viscoelastic_fast_path.csv")
    args = parser.parse_args()
    mesh = {"refinement": args.refinement}
    peak = args.peak
    histories = {
        "mode 1": mode1_history(peak, on_s=3.0, off_s=2.0, cycles=2, rise_s=0.01,
                                first_step_s=1e-3, growth=1.25, max_step_s=0.05),
        "mode 2": mode2_history(peak, rate_mbar_s=25.0, step_s=0.1),
    }
    rows, timings = [], []
    for k, skin in enumerate(draw_skins(args.draws, args.seed, args.x2_over_x1d, args.x1d)):
        x1d, x1h = skin["x1d"], skin["x1d"] * skin["ratio"]
        x2d = skin["x2_over_x1d"] * x1d
        prony = Prony(skin["g"], skin["tau"])
        label = (f"draw {k}: X1d {x1d:.3f} MPa, X1h/X1d {skin['ratio']:.3f}, g {skin['g'][0]:.2f}/"
                 f"{skin['g'][1]:.2f}, tau {1e3 * skin['tau'][0]:.1f} ms/{skin['tau'][1]:.2f} s, "
                 f"X2d/X1d {skin['x2_over_x1d']:.2f}")
        probe = Probe(args.probe)
        start = time.perf_counter()
        elastic = simulate(Skin.two_layer(x1d, x1h, x2d=x2d), probe,
                           pressures_mbar=np.arange(0.0, peak + 1, 5.0), mesh=mesh)
        t_el = time.perf_counter() - start
        if not elastic.converged:
            print(f"{label}: long-time elastic curve stops at {elastic.last_converged_mbar:g} mbar; skipped")
            continue
        print(label, flush=True)
        for name, hist in histories.items():
            fe = simulate_history(Skin.two_layer(x1d, x1h, x2d=x2d, spectrum=prony), hist.times_s,
                                  hist.pressure_mbar, probe, mesh=mesh, branches=args.branches)
            if not fe.converged:
                print(f"  {name}: FE stopped: {fe.reason}")
                continue
            start = time.perf_counter()
            fast = fast_history(elastic, prony, hist.times_s, hist.pressure_mbar)
            t_fast = time.perf_counter() - start
            plain = np.interp(hist.pressure_mbar, elastic.pressure_mbar, elastic.deflection_mm)
            if name == "mode 1":
                scale = fe.deflection_mm[np.flatnonzero(hist.phase == "hold")[hist.times_s[hist.phase == "hold"] <= 3.0 + 1e-9][-1]]
            else:
                scale = np.max(fe.deflection_mm)
            timings.append(dict(draw=k, history=name, fe_s=fe.seconds, steps=fe.steps,
                                iterations=fe.newton_iterations, elastic_s=t_el, fast_ms=1e3 * t_fast))
            print(f"  {name}: FE {fe.seconds:.2f} s ({fe.steps} steps, {fe.newton_iterations} "
                  f"iterations, {fe.dofs} DOFs); Uf {1e3 * scale:.1f} µm; fast path {1e3 * t_fast:.2f} ms")
            for model_name, m in (("fast path", fast), ("elastic", plain)):
                for phase, (mx, rms, mxp, rmsp) in errors(m, fe.deflection_mm, hist.phase, scale).items():
                    rows.append(dict(draw=k, history=name, model=model_name, phase=phase, uf_um=1e3 * scale,
                                     max_um=mx, rms_um=rms, max_pct=mxp, rms_pct=rmsp, **skin))
            if k == 0 and name == "mode 1":
                # the FE's own time-step error: every step halved
                t = hist.times_s
                t2 = np.sort(np.concatenate([t, 0.5 * (t[1:] + t[:-1])]))
                p2 = np.interp(t2, t, hist.pressure_mbar)
                fine = simulate_history(Skin.two_layer(x1d, x1h, x2d=x2d, spectrum=prony), t2, p2, probe,
                                    mesh=mesh, branches=args.branches)
                d = np.abs(fine.deflection_mm[::2] - fe.deflection_mm) * 1e3
                print(f"  FE time-step error (steps halved): max {d.max():.3f} µm "
                      f"({100 * d.max() / (1e3 * scale):.3f} % of Uf)")
    table = pd.DataFrame(rows)
    out = Path(__file__).parent / "out"
    out.mkdir(exist_ok=True)
    table.to_csv(out / args.out, index=False)
    print()
    print("| history | model | phase | max µm (worst draw) | max % of Uf (worst) | RMS % of Uf (median of draws) |")
    print("|---|---|---|---|---|---|")
    for (hist, model, phase), g in table.groupby(["history", "model", "phase"], sort=False):
        print(f"| {hist} | {model} | {phase} | {g.max_um.max():.1f} | {g.max_pct.max():.2f} | "
              f"{g.rms_pct.median():.2f} |")
    print()
    print("| draw | history | fast path max % of Uf (any phase) | elastic max % |")
    print("|---|---|---|---|")
    for (k, hist), g in table.groupby(["draw", "history"], sort=False):
        print(f"| {k} | {hist} | {g[g.model == 'fast path'].max_pct.max():.2f} | "
              f"{g[g.model == 'elastic'].max_pct.max():.1f} |")
    t = pd.DataFrame(timings)
    if len(t):
        print()
        for hist, g in t.groupby("history"):
            print(f"{hist}: FE history solve median {g.fe_s.median():.2f} s ({g.steps.median():.0f} steps, "
                  f"{g.iterations.median():.0f} iterations); elastic curve {g.elastic_s.median():.2f} s; "
                  f"fast path {g.fast_ms.median():.2f} ms")


if __name__ == "__main__":
    main()
