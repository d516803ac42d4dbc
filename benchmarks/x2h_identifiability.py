"""Is X2 of the hypodermis identifiable from 2 and 6 mm suction curves? A profile of E.

A cause ``hypodermis_stiffening`` (keyword x2h, a modulus: coordinate X2h / X1d)
is declared on the fly, as a user would add it to ``diagnosis.causes``, and its
ray space is built on the coarse settings of config/ci.yaml (refinement 0.5).
For virtual experiments (FE, both probes, noise 2 µm) with

* hypodermis stiffening hidden (X2h = k X1h),
* dermis stiffening hidden (X2d / X1d = 10),
* no effect,

the profile ``chi2_min(X2h) - chi2_min`` is computed: (X1d, X1h) are refitted at
every fixed X2h.  X2h is identifiable where the profile rises above 3.84 (95 %
profile-likelihood interval) inside the range; a flat profile means the
neo-Hookean moduli absorb X2h.  Also prints the diagnosis of the hidden
X2h experiments with the registry extended by this cause.

    python benchmarks/x2h_identifiability.py [--space-dir DIR] [--workers 2]
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
from pathlib import Path

import numpy as np
import yaml
from scipy.optimize import least_squares

ROOT = Path(__file__).resolve().parents[1]
X2H_NODES = [0.0, 0.0125, 0.025, 0.05, 0.1, 0.2]  # X2h / X1d


def profile(space, fd, coords, theta0):
    """chi^2 minimised over (log X1d, log r) at each fixed coordinate."""
    from skinsuction.diagnose import ModelCurves

    model = ModelCurves(space, fd)
    lo, hi = model.lower[:2], model.upper[:2]

    def res(x2, c):
        th = np.array([[x2[0], x2[1], c]])
        out = []
        for p, m in model(th).items():
            d = fd[p]
            out.append((d.deflection_mm - m[0]) * 1e3 / d.sigma_um)
        r = np.concatenate(out)
        return np.where(np.isfinite(r), r, 1e3)

    out, x = [], np.clip(np.asarray(theta0[:2], float), lo, hi)
    for c in coords:
        best = None
        for start in (x, np.clip(theta0[:2], lo, hi)):
            s = least_squares(res, start, args=(c,), bounds=(lo, hi), x_scale=0.05,
                              xtol=1e-12, ftol=1e-12)
            if best is None or s.cost < best.cost:
                best = s
        x = best.x
        out.append((c, 2 * best.cost, 10 ** x[0], 10 ** (x[0] + x[1])))
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--space-dir", default=None, help="where to build/keep the rays")
    ap.add_argument("--workers", type=int, default=1)
    args = ap.parse_args(argv)

    from skinsuction.diagnose import Cause, FitData, Settings, diagnose_file, fit_model, prepare_data, registry_from_config
    from skinsuction.evaluation import virtual_experiment, write_csv
    from skinsuction.space import RaySpec, build_ray_spaces
    from skinsuction.measured import load_measured

    cfg = yaml.safe_load((ROOT / "config" / "ci.yaml").read_text())
    d = cfg["scale_free_space"]
    spec = RaySpec.from_config(d, cfg.get("mesh"), cfg.get("mesh_fallback"))
    causes = registry_from_config(d["causes"])
    causes["hypodermis_stiffening"] = Cause(
        "hypodermis_stiffening", "x2h", "X2h", "MPa", True, 0.0, tuple(X2H_NODES),
        hypothesis="the hypodermis stiffens faster than neo-Hookean",
        description="second-order modulus X2 of the hypodermis (MPa)")
    out = Path(args.space_dir or tempfile.mkdtemp(prefix="x2h-"))
    spaces = build_ray_spaces(spec, causes, out_dir=out, workers=args.workers)
    sp = spaces["hypodermis_stiffening"]
    x1d, ratio = 0.028, 0.01
    x1h = ratio * x1d
    cases = [("X2h = 5 X1h", causes["hypodermis_stiffening"], 5 * x1h),
             ("X2h = 20 X1h", causes["hypodermis_stiffening"], 20 * x1h),
             ("X2d / X1d = 10", causes["strain_stiffening"], 10 * x1d),
             ("none", None, None)]
    coords = np.array(X2H_NODES[:1] + list(np.linspace(0.0025, X2H_NODES[-1], 24)))
    settings = Settings(noise_um=2.0)
    print(f"X1d = {x1d} MPa, X1h = {x1h:.3g} MPa (X1h/X1d = {ratio}), noise 2 µm, "
          f"mesh {spec.mesh}; profile over X2h / X1d in 0..{X2H_NODES[-1]}")
    for label, cause, value in cases:
        ve = virtual_experiment(x1d, x1h, cause, value, noise_um=2.0, seed=7, mesh=spec.mesh)
        with tempfile.TemporaryDirectory() as tmp:
            csv = write_csv(ve, Path(tmp) / "v.csv")
            data = load_measured(csv)
            fd, noise, _ = prepare_data(data, [2.0, 6.0], settings)
            f = fit_model(sp, fd, seed=0, repeats=2)
            # the coarse grid, and a fine one around the best value
            fine = np.clip(f.theta[2] + np.linspace(-0.01, 0.01, 21), 0, X2H_NODES[-1])
            grid = np.unique(np.concatenate([coords, fine]))
            prof = profile(sp, fd, grid, f.theta)
            rep = diagnose_file(csv, out, settings, spaces=spaces)
            without = {k: v for k, v in spaces.items() if k != "hypodermis_stiffening"}
            rep0 = diagnose_file(csv, out, settings, spaces=without)
        chi = np.array([c for _, c, _, _ in prof])
        dchi = chi - min(chi.min(), f.chi2)
        inside = grid[dchi <= 3.84]
        if not inside.size:
            inside = grid[[int(np.argmin(dchi))]]
        truth = "" if cause is None or cause.keyword != "x2h" else f" (true {value / x1d:.3g})"
        print(f"\n{label}: best X2h / X1d = {f.theta[2]:.3g}{truth}, chi2 {f.chi2:.1f} "
              f"for {f.n_points} points; 95 % profile interval of X2h / X1d: "
              f"{inside.min():.3g}..{inside.max():.3g} (range 0..{X2H_NODES[-1]})")
        print("   X2h/X1d  delta chi2   X1d (MPa)   X1h (MPa)")
        for (c, _, a, b), dc in zip(prof, dchi):
            if c in coords:
                print(f"   {c:7.4f}  {dc:9.2f}   {a:.4g}   {b:.4g}")
        cands = {c["cause"]: round(c["delta_bic"], 1) for c in rep["candidates"]}
        print(f"   diagnosis with hypodermis_stiffening in the registry: {rep['cause']} "
              f"(delta BIC {cands}; baseline misfit {rep['baseline']['systematic_misfit']})")
        print(f"   diagnosis with the default registry: {rep0['cause']} ({rep0['verdict']}; "
              + ", ".join(f"{c['cause']}: delta BIC {c['delta_bic']:.0f}, misfit left "
                          f"{c['systematic_misfit']}" for c in rep0["candidates"]) + ")")
    return 0


if __name__ == "__main__":
    sys.exit(main())
