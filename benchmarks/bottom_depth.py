"""Where the bottom stops mattering: M against the hypodermis depth t_h / a.

    python benchmarks/bottom_depth.py [--probe 6] [--t-d 1.0]

Runs the FE model (reference mesh, fixed bottom, neo-Hookean, X1d = 0.01 MPa) for
X1h/X1d = 1e-3, 0.03, 0.3, 1 and 2 with the hypodermis t_h = a/4 ... 16 a (a the
aperture radius) to p = 100 mbar (p/X1d = 10 000 mbar/MPa), and prints M at 20,
50 and 100 mbar and the change of M from each depth to the next (doubling). By
geometric similarity the result holds for every probe at the same t_d/a and t_h/a.
Asserts nothing.
"""

import argparse

import numpy as np

from skinsuction.model import Skin, simulate


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--probe", type=float, default=6.0)
    ap.add_argument("--t-d", type=float, default=1.0)
    args = ap.parse_args(argv)
    a = args.probe / 2
    p = np.arange(0.0, 101.0, 10.0)
    depths = [0.25, 0.5, 1, 2, 4, 8, 16]
    print(f"{args.probe:g} mm probe, t_d = {args.t_d:g} mm (t_d/a = {args.t_d / a:.3g}), "
          "X1d = 0.01 MPa")
    print("X1h/X1d  t_h/a   M(20)    M(50)    M(100) mbar (mm)   change from the depth before")
    for r in (1e-3, 0.03, 0.3, 1.0, 2.0):
        before = None
        for d in depths:
            c = simulate(Skin.two_layer(0.01, 0.01 * r, t_d=args.t_d, t_h=d * a), probe=args.probe, pressures_mbar=p)
            m = np.full(p.size, np.nan)
            m[: len(c.deflection_mm)] = c.deflection_mm
            if not c.converged:
                m[p > c.last_converged_mbar] = np.nan
            pick = m[[2, 5, 10]]
            change = ("" if before is None else
                      "  ".join(f"{100 * (x / y - 1):+.3f} %" for x, y in zip(pick, before)))
            print(f"{r:7.3g}  {d:5.3g}  " + "  ".join(f"{x:7.4f}" for x in pick) + f"   {change}",
                  flush=True)
            before = pick


if __name__ == "__main__":
    main()
