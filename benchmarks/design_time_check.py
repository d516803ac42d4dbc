"""`skinsuction design` for mode 1 and mode 2 against FE time curves identified.

    python benchmarks/design_time_check.py [--skins 10] [--seed 0] [--workers 1]
        [--designs 2+6@100:mode1] [--x1d 0.02 0.09]

Skins from the default box (X1h/X1d 0.003-0.3, 1 mm layers; X1d in --x1d, where the FE
time solves converge under a hold; one Prony term, g 0.1-1 and tau 0.1-1 s, the box's
spectrum). For each skin and design, `design` predicts the 95 % intervals of X1d, X1h
(long-time), g and tau (the fast path's Fisher information at the truth); then the same
skin is measured: an FE time solve of each probe under the design's suction history
(mode 1: 3 s on, 3 s off, 2 cycles after 0.5 s at rest; mode 2: up and down at 25
mbar/s), sampled at 100 Hz with 2 µm noise and read at 0.01 mm, identified by
`identify` (one term, the FE correction of the fit, as a user runs it). Prints per
design and parameter the median predicted and realised relative half-widths, and how
often the realised interval covers the truth.

Asserts nothing; writes every row to benchmarks/out/design_time_check.csv.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd
from _pool import run_rows

NOISE_UM, READING_MM = 2.0, 0.01
PARAMS = {"X1d": "X1d", "X1h": "X1h", "g_1": "g_1", "tau_1": "tau_1"}


def _design(text):
    from skinsuction.design import Design

    head, _, protocol = text.partition(":")
    probes, _, mbar = head.partition("@")
    return Design(tuple(float(p) for p in probes.split("+")), float(mbar),
                  noise_um=NOISE_UM, resolution_mm=READING_MM, protocol=protocol or "mode1")


def _suction(design):
    from skinsuction.evaluation import mode1_suction, mode2_suction

    if design.protocol == "mode1":
        on, off, n = design.timing
        return mode1_suction(design.max_mbar, on_s=on, off_s=off, cycles=int(n))
    return mode2_suction(design.max_mbar, rate_mbar_s=design.timing[0])


def _run(job):
    from types import SimpleNamespace

    from skinsuction.design import predict_skin, relative_halfwidth
    from skinsuction.diagnose import Settings
    from skinsuction.evaluation import virtual_curve, write_time_csv
    from skinsuction.identify.time_curves import identify_time_data
    from skinsuction.measured import load_time_curves
    from skinsuction.space import SHIPPED_SPACE_DIR, load_space, read_ray_spaces
    from skinsuction.viscoelastic import Prony

    skin, text, seed = job
    design = _design(text)
    row = {"design": design.name, **skin, "seed": seed}
    t0 = time.process_time()
    pred = predict_skin(skin, design, read_ray_spaces(SHIPPED_SPACE_DIR), Settings())
    row["predict_cpu_s"] = time.process_time() - t0
    row.update({f"pred_{k}": v for k, v in pred.items() if k not in ("design", "skin")})
    if pred.get("beyond_space"):
        return row
    x1d = float(skin["x1d_mpa"])
    truth = {"X1d": x1d, "X1h": x1d * float(skin["x1h_ratio"]), "g_1": float(skin["g_1"]),
             "tau_1": float(skin["tau_1_s"])}
    t0 = time.perf_counter()
    curves = []
    try:
        for k, probe in enumerate(design.probes_mm):
            t, p, d, _, _ = virtual_curve(truth["X1d"], truth["X1h"],
                                          Prony([truth["g_1"]], [truth["tau_1"]]),
                                          _suction(design), probe_mm=probe,
                                          noise_mm=1e-3 * NOISE_UM, resolution_mm=READING_MM,
                                          seed=seed * 10 + k)
            curves.append((probe, t, p, d))
    except RuntimeError as err:
        row["real_error"] = f"FE: {err}"
        return row
    row["fe_s"] = time.perf_counter() - t0
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "curves.csv"
        write_time_csv(path, curves, ["synthetic: design_time_check"])
        t0 = time.process_time()
        try:
            r = identify_time_data(load_time_curves(path), load_space(), terms=1, seed=seed)
        except Exception as err:  # recorded; the other skins go on
            row["real_error"] = f"{type(err).__name__}: {' '.join(str(err).split())}"
            return row
    row["identify_cpu_s"] = time.process_time() - t0
    for k, v in truth.items():
        iv = r["intervals"][k]
        ns = SimpleNamespace(**iv)
        row[f"real_{k}_halfwidth"], row[f"real_{k}_bounded"] = relative_halfwidth(
            k, iv["estimate"], ns)
        row[f"real_{k}_covers"] = bool(iv["lower"] <= v <= iv["upper"])
    return row


def summary(df: pd.DataFrame) -> list:
    lines = []
    for design, g in df.groupby("design", sort=False):
        ok = g[g.get("real_X1d_halfwidth", pd.Series(np.nan, index=g.index)).notna()]
        lines.append(f"{design}: {len(g)} skins, {int(g['pred_beyond_space'].fillna(False).sum())}"
                     f" beyond the space, {len(ok)} identified")
        for k in PARAMS:
            if f"real_{k}_halfwidth" not in ok or not len(ok):
                continue
            pw = ok[f"pred_{k}_halfwidth"].astype(float)
            rw = ok[f"real_{k}_halfwidth"].astype(float)
            cov = ok[f"real_{k}_covers"].astype(bool)
            lines.append(f"  {k}: half-width median predicted {100 * pw.median():.3g} %, "
                         f"realised {100 * rw.median():.3g} % (ratio of medians "
                         f"{rw.median() / pw.median():.2f}); realised intervals cover the "
                         f"truth in {cov.sum()}/{len(cov)}")
    return lines


def main(argv=None):
    from skinsuction.design import Box

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--skins", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--designs", nargs="+", default=["2+6@100:mode1"])
    ap.add_argument("--x1d", nargs=2, type=float, default=[0.02, 0.09])
    ap.add_argument("--out", default="benchmarks/out/design_time_check.csv")
    args = ap.parse_args(argv)

    skins = Box(x1d_mpa=tuple(args.x1d)).draw(args.skins, args.seed)
    jobs = [(r._asdict(), d, args.seed + 100 * i + j) for j, d in enumerate(args.designs)
            for i, r in enumerate(skins.itertuples(index=False))]
    df, seconds = run_rows(_run, jobs, args.workers, args.out)
    print(f"{args.skins} skins x {len(args.designs)} designs, {seconds:.0f} s wall on "
          f"{args.workers} workers; 2 µm noise, 0.01 mm reading, 100 Hz")
    print("\n".join(summary(df)))
    print(f"written: {Path(args.out)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
