"""Make the synthetic suction tests of data/ (not measurements).

The FE model (skinsuction.model.simulate; reference mesh, fixed bottom,
neo-Hookean) at X1d = 0.04 MPa, X1h = 5.0e-4 MPa (both off the grid of the
paper's space), pressures 0, 2, ..., 100 mbar, plus Gaussian noise of standard
deviation 1.5 µm (NumPy seed 0) on every deflection but the one at 0 mbar (the
instrument zero):

* ``example_measured.csv``: 6 and 2 mm probes, both layers 1 mm (the paper's);
* ``example_measured_4_8mm.csv``: the 4 and 8 mm probes, both layers 1 mm;
* ``example_measured_layers.csv``: 6 and 2 mm probes on a 1.3 mm dermis over a
  3 mm hypodermis, given in its header (``# dermis_thickness_mm: 1.3`` ...), as
  a study that measured them by ultrasound would.

    python data/make_example_measured.py [NAME ...]   # default: all three
"""

import subprocess
import sys
from pathlib import Path

import numpy as np

from skinsuction.model import Skin, simulate
from skinsuction.provenance import git_info

X1D, X1H = 0.04, 5.0e-4  # MPa
NOISE_SD_MM = 1.5e-3
SEED = 0
PRESSURES = np.arange(0.0, 101.0, 2.0)


EXAMPLES = {
    "example_measured.csv": dict(probes=(6.0, 2.0), t_d=1.0, t_h=1.0, given=False),
    "example_measured_4_8mm.csv": dict(probes=(8.0, 4.0), t_d=1.0, t_h=1.0, given=False),
    "example_measured_layers.csv": dict(probes=(6.0, 2.0), t_d=1.3, t_h=3.0, given=True),
}


def main(*names):
    for name in names or EXAMPLES:
        make(Path(__file__).with_name(name), **EXAMPLES[name])


def make(out, probes, t_d, t_h, given):
    rng = np.random.default_rng(SEED)
    rows = []
    for probe in probes:
        c = simulate(Skin.two_layer(X1D, X1H, t_d=t_d, t_h=t_h, bottom="fixed"), probe=probe, pressures_mbar=PRESSURES, mesh={"refinement": 1.0})
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
    layers = ("layers 1 mm" if (t_d, t_h) == (1.0, 1.0)
              else f"dermis {t_d:g} mm, hypodermis {t_h:g} mm")
    header = [
        "# SYNTHETIC EXAMPLE, NOT A MEASUREMENT. Made by data/make_example_measured.py",
        f"# with the skinsuction FE model (reference mesh, fixed bottom, {layers}, neo-Hookean)",
        f"# at X1d = 0.04 MPa and X1h = 5.0e-4 MPa, {' and '.join(f'{p:g}' for p in probes)} mm "
        "probes, plus Gaussian noise of sd 1.5 um (seed 0).",
        "subject: synthetic",
        *([f"dermis_thickness_mm: {t_d:g}", "dermis_thickness_sd_mm: 0.1",
           f"hypodermis_thickness_mm: {t_h:g}"] if given else []),
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
