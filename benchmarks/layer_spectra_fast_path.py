"""The per-layer fast path against FE time solves with a spectrum per layer (prints
figures; asserts nothing).

Draws (seeded): X1d log-uniform 0.04-0.15 MPa, X1h/X1d 0.01-0.3, one Prony term per
layer, tau log-uniform 0.1-1 s each; the dermis's g log-uniform 0.1-1 or 1e-4 (it does
not creep), the hypodermis's 0.1-2 or 1e-4, at least one layer creeping.  Mode 1, 400
mbar, 3 s on / 2 s off, one cycle, 100 Hz, on the 2 and 8 mm probes: the FE time solve
(``virtual_skin_curve``, no noise) against the per-layer fast path
(``TimeCurveModel(..., layers=True)`` on the shipped space, at the true parameters) and
against the shared-spectrum fast path with the spectrum of the layer that carries most
of the compliance.  Errors per phase as % of Uf (the curve's largest deflection).

    python benchmarks/layer_spectra_fast_path.py [--draws 10] [--seed 0]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

PROBES = (2.0, 8.0)


def draw(rng):
    kind = rng.integers(3)  # 0 dermis only, 1 hypodermis only, 2 both
    return {"x1d": 10 ** rng.uniform(np.log10(0.04), np.log10(0.15)),
            "ratio": 10 ** rng.uniform(-2, np.log10(0.3)),
            "g_d": 10 ** rng.uniform(-1, 0) if kind != 1 else 1e-4,
            "tau_d": 10 ** rng.uniform(-1, 0),
            "g_h": 10 ** rng.uniform(-1, np.log10(2)) if kind != 0 else 1e-4,
            "tau_h": 10 ** rng.uniform(-1, 0),
            "kind": ("dermis", "hypodermis", "both")[kind]}


def main():
    from skinsuction.evaluation import mode1_suction, virtual_skin_curve, write_time_csv
    from skinsuction.identify import TimeCurveModel, fit_data_of
    from skinsuction.measured import load_time_curves
    from skinsuction.model import Skin
    from skinsuction.space import load_space
    from skinsuction.viscoelastic import Prony

    ap = argparse.ArgumentParser()
    ap.add_argument("--draws", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    space = load_space()
    tmp = Path(tempfile.mkdtemp())
    suction = mode1_suction(400.0, on_s=3.0, off_s=2.0, cycles=1)
    rows, start = [], time.perf_counter()
    for k in range(args.draws):
        s = draw(rng)
        skin = Skin.two_layer(s["x1d"], s["x1d"] * s["ratio"],
                              spectrum=Prony([s["g_d"]], [s["tau_d"]])).replace(
            {"hypodermis.spectrum.g[0]": s["g_h"], "hypodermis.spectrum.tau_s[0]": s["tau_h"]})
        curves = []
        try:
            for probe in PROBES:
                t, p, _, exact, _ = virtual_skin_curve(skin, suction, probe_mm=probe,
                                                       noise_mm=0.0, resolution_mm=0.0)
                curves.append((probe, t, p, exact))
        except RuntimeError as err:
            print(f"draw {k}: FE stopped ({err}); skipped")
            continue
        data = load_time_curves(write_time_csv(tmp / f"{k}.csv", curves, ["FE"]))
        fd = [fit_data_of(c, noise_sd_mm=0.001) for c in data.curves]
        rays = {d.probe_mm: space.probe(d.probe_mm).space for d in fd}
        layers = TimeCurveModel(rays, fd, terms=1, layers=True)
        base = [np.log10(s["x1d"]), np.log10(s["ratio"])]
        theta = np.array(base + list(np.log10([s["g_d"], s["tau_d"], s["g_h"], s["tau_h"]])))
        shared = TimeCurveModel(rays, fd, terms=1)
        for d, m in zip(fd, layers(theta[None])):
            beta = float(layers.hypodermis_share(theta[None], d.probe_mm, 400.0)[0])
            main_layer = ("h" if beta > 0.5 else "d")
            th_sh = np.array(base + list(np.log10([s[f"g_{main_layer}"], s[f"tau_{main_layer}"]])))
            m_sh = next(mm for dd, mm in zip(fd, shared(th_sh[None])) if dd is d)
            exact = d.deflection_mm
            uf = float(exact.max())
            for name, model in (("per layer", m[0]), ("shared (main layer)", m_sh[0])):
                err = 100 * np.abs(model - exact) / uf
                for ph in ("on", "release", "off"):
                    sel = d.phase == ph
                    rows.append({"draw": k, **s, "probe_mm": d.probe_mm, "beta": beta,
                                 "model": name, "phase": ph, "uf_um": 1e3 * uf,
                                 "max_pct": float(err[sel].max()),
                                 "rms_pct": float(np.sqrt(np.mean(err[sel] ** 2)))})
        print(f"draw {k} ({s['kind']} creeps): done ({time.perf_counter() - start:.0f} s)",
              flush=True)
    df = pd.DataFrame(rows)
    out = Path(__file__).parent / "out"
    out.mkdir(exist_ok=True)
    df.to_csv(out / "layer_spectra_fast_path.csv", index=False)
    print("\n| model | probe | phase | max % of Uf (worst draw) | RMS % of Uf (median) |")
    print("|---|---|---|---|---|")
    for (model, probe, ph), g in df.groupby(["model", "probe_mm", "phase"], sort=False):
        print(f"| {model} | {probe:g} mm | {ph} | {g.max_pct.max():.2f} | {g.rms_pct.median():.2f} |")
    print(f"\nhypodermis share beta: 2 mm {df[df.probe_mm == 2].beta.median():.2f}, "
          f"8 mm {df[df.probe_mm == 8].beta.median():.2f} (medians); "
          f"{df.draw.nunique()} draws, {time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    main()
