"""Make data/example_measured.csv: a synthetic suction test (not a measurement).

The FE model (skinsuction.model.simulate; reference mesh, fixed bottom, both
layers 1 mm thick, neo-Hookean) at X1d = 0.04 MPa, X1h = 5.0e-4 MPa (both off
the grid of the paper's space), pressures 0, 2, ..., 100 mbar, 6 mm and 2 mm
probes, plus Gaussian noise of standard deviation 1.5 µm (NumPy seed 0) on every
deflection but the one at 0 mbar (the instrument zero).

    python data/make_example_measured.py [OUT.csv]
"""

import subprocess
import sys
from pathlib import Path

import numpy as np

from skinsuction.model import simulate
from skinsuction.provenance import git_info

X1D, X1H = 0.04, 5.0e-4  # MPa
NOISE_SD_MM = 1.5e-3
SEED = 0
PRESSURES = np.arange(0.0, 101.0, 2.0)


def main(out=Path(__file__).with_name("example_measured.csv")):
    rng = np.random.default_rng(SEED)
    rows = []
    for probe in (6.0, 2.0):
        c = simulate(X1D, X1H, probe_mm=probe, bottom="fixed", pressures_mbar=PRESSURES,
                     mesh={"refinement": 1.0})
        if not c.converged:
            raise SystemExit(f"{probe:g} mm: the model did not converge ({c.reason})")
        m = c.deflection_mm + rng.normal(0.0, NOISE_SD_MM, PRESSURES.size)
        m[PRESSURES == 0] = 0.0
        rows += [f"{probe:g},{p:g},{x:.5f}" for p, x in zip(PRESSURES, m)]
    commit = git_info().get("commit") or "unknown"
    model_dir = Path(__file__).resolve().parents[1] / "src" / "skinsuction" / "model"
    status = subprocess.run(["git", "status", "--porcelain", "--", str(model_dir)],
                            capture_output=True, text=True, cwd=model_dir).stdout
    if status.strip():
        commit += " (model sources with uncommitted changes)"
    header = [
        "# SYNTHETIC EXAMPLE, NOT A MEASUREMENT. Made by data/make_example_measured.py",
        "# with the skinsuction FE model (reference mesh, fixed bottom, layers 1 mm, neo-Hookean)",
        "# at X1d = 0.04 MPa and X1h = 5.0e-4 MPa, plus Gaussian noise of sd 1.5 um (seed 0).",
        "subject: synthetic",
        f"x1d_true_mpa: {X1D:g}",
        f"x1h_true_mpa: {X1H:g}",
        f"noise_sd_um: {1e3 * NOISE_SD_MM:g}",
        f"noise_seed: {SEED}",
        f"model_git_commit: {commit}",
    ]
    text = "\n".join(h if h.startswith("#") else f"# {h}" for h in header)
    text += "\nprobe_mm,pressure_mbar,deflection_mm\n" + "\n".join(rows) + "\n"
    Path(out).write_text(text, encoding="utf-8")
    print(f"wrote {out}")


if __name__ == "__main__":
    main(*sys.argv[1:])
