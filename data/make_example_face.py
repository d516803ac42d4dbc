"""Make data/example_face_mode1.csv: an FE virtual experiment of the face protocol (not a measurement).

The skin of data/example_face_skin.yaml (X1d 0.018, X1h 3e-4, X2d 0.1 MPa; both layers
with the spectrum g (0.5, 1.5), tau (0.05, 2.5) s; the paper's 1 mm layers) under the
2 mm probe, Cutometer mode 1 at 450 mbar, 3 s on / 3 s off, 2 cycles, solved in time
by the FE model (``skinsuction simulate``, not the fast path); Gaussian noise of sd
2 µm, rounded to 0.01 mm (the Cutometer's resolution); NumPy seed 35.  Its first cycle
gives R0 0.228, R2 0.664, R5 0.642, R7 0.484 (published face ranges: R0 0.20-0.33, R2
0.66-0.82, R5 0.60-0.92, R7 0.37-0.52).  At X1d 0.018, 450 mbar is a load of 25 000
mbar/MPa: beyond the space's even steps (2·10⁴), in its load tail.

    python data/make_example_face.py      # about a minute
"""

import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd

HERE = Path(__file__).resolve().parent
NOISE_MM, RESOLUTION_MM, SEED = 0.002, 0.01, 35


def main():
    with tempfile.TemporaryDirectory() as tmp:
        clean = Path(tmp) / "clean.csv"
        subprocess.run([sys.executable, "-m", "skinsuction", "simulate", "--probe", "2",
                        "--skin", str(HERE / "example_face_skin.yaml"),
                        "--mode1", "450,3,3,2", "--measured-format", "--out", str(clean)],
                       check=True)
        frame = pd.read_csv(clean, comment="#")
    rng = np.random.default_rng(SEED)
    noisy = frame["deflection_mm"] + rng.normal(0.0, NOISE_MM, len(frame))
    frame["deflection_mm"] = np.round(noisy / RESOLUTION_MM) * RESOLUTION_MM
    out = HERE / "example_face_mode1.csv"
    header = ("# SYNTHETIC EXAMPLE, NOT A MEASUREMENT. Made by data/make_example_face.py: FE mode 1 "
              "(2 mm, 450 mbar, 3 s on / 3 s off, 2 cycles) of data/example_face_skin.yaml\n"
              "# (X1d 0.018, X1h 3e-4, X2d 0.1 MPa; g (0.5, 1.5), tau (0.05, 2.5) s in both layers), "
              "Gaussian noise sd 2 um, rounded to 0.01 mm; NumPy seed 35.\n")
    tmp_out = out.with_suffix(".tmp")
    with open(tmp_out, "w", encoding="utf-8") as f:
        f.write(header)
        frame.to_csv(f, index=False, float_format="%.6g")
    tmp_out.replace(out)
    print(f"wrote {out} ({len(frame)} samples)")


if __name__ == "__main__":
    main()
