"""How far the FE rays reach in load: the Cutometer's 500 mbar on soft forearm skin.

Forearm suction studies report X1d down to about 0.007 MPa and Cutometers apply up
to 500 mbar: a load p/X1d of 71 400 mbar/MPa, 3.6 times the default space's
``load.max`` (20 000). This solves the space's own rays (``compute_ray``: the
default mesh, then the configured fallback meshes, spliced) at ``x1d_ref`` to that
load, for every probe, a span of X1h/X1d and of dermis stiffening X2d/X1d, and
prints where each stops: the load reached, the X1d down to which 500 mbar (and
300 mbar) is covered, the largest principal stretch and the solver's reason.
It asserts nothing; the table is the frontier the closing notes and
docs/scale_free_space.md quote.

    OMP_NUM_THREADS=1 python benchmarks/high_suction_frontier.py [--processes 2] [--out FILE.csv]
"""

from __future__ import annotations

import argparse
import os
import re
import time
from multiprocessing import Pool
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import yaml  # noqa: E402

from skinsuction.space import RaySpec, compute_ray, ray_id  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
TARGET_LOAD = 500.0 / 0.007  # mbar/MPa: 500 mbar at X1d = 0.007 MPa
PROBES = (2.0, 4.0, 6.0, 8.0)
RATIOS = (1e-3, 1e-2, 0.1, 1.0)
STIFFENING = (0.0, 10.0)  # X2d / X1d


def _spec() -> RaySpec:
    config = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    section = dict(config["scale_free_space"])
    section["load"] = {**section["load"], "max": TARGET_LOAD}
    return RaySpec.from_config(section, config.get("mesh"))


def _one(args):
    probe, ratio, stiff = args
    spec = _spec()
    x1d = spec.x1d_ref
    params = {"probe_mm": probe, "bottom": spec.bottom, "x1d": x1d, "x1h": ratio * x1d}
    if stiff:
        params["x2d"] = stiff * x1d
    t0 = time.process_time()
    curve, _, info = compute_ray(ray_id(params), spec.pressures_mbar, spec.mesh, spec.fallback,
                                 spec.fallback_below_mbar)
    reach = float(info["last_converged_mbar"]) / x1d
    stretch = re.search(r"largest principal stretch ([0-9.]+)", info["reason"])
    return {"probe_mm": probe, "x1h_over_x1d": ratio, "x2d_over_x1d": stiff,
            "load_reached": round(reach), "complete": bool(info["converged"]),
            "x1d_min_500mbar": 500.0 / reach if reach > 0 else np.inf,
            "x1d_min_300mbar": 300.0 / reach if reach > 0 else np.inf,
            "stretch_at_stop": float(stretch.group(1)) if stretch else np.nan,
            "mesh_fallback": info["mesh_fallback"],
            "cpu_s": round(time.process_time() - t0, 1),
            "reason": " ".join(info["reason"].split())[:120]}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--processes", type=int, default=1)
    ap.add_argument("--out", type=Path, default=None, help="also write the table as CSV")
    args = ap.parse_args(argv)
    jobs = [(p, r, s) for p in PROBES for r in RATIOS for s in STIFFENING]
    t0 = time.perf_counter()
    with Pool(args.processes) as pool:
        rows = pool.map(_one, jobs, chunksize=1)
    frame = pd.DataFrame(rows)
    pd.set_option("display.width", 200)
    print(f"target load {TARGET_LOAD:.0f} mbar/MPa (500 mbar at X1d = 0.007 MPa); "
          f"{len(rows)} rays, {time.perf_counter() - t0:.0f} s wall, "
          f"{frame['cpu_s'].sum():.0f} CPU-s")
    print(frame.drop(columns=["reason"]).to_string(index=False))
    print("\nX1d (MPa) down to which 500 mbar is covered, worst ratio, per probe and X2d/X1d:")
    print(frame.groupby(["probe_mm", "x2d_over_x1d"])["x1d_min_500mbar"].max()
          .unstack().round(4).to_string())
    if args.out:
        frame.to_csv(args.out, index=False)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
