"""The model against CalculiX on nested meshes: M(100 mbar) of the reference skin
under the 2 and 6 mm probes (prints a table; asserts nothing).

At each refinement level k (every element of the default mesh split into k^2,
the fan's rings and spokes included) the same mesh is solved by this model's
fast path and by CalculiX (``ccx``, the deck of
:func:`skinsuction.model.inp_deck`), with the probe wall off on both sides
(the deck omits it; for this skin it is never touched: the column "wall on" is
this model with it). The relative difference is between the two codes on one
mesh; the mesh limit of each code is a Richardson extrapolation of its three
finest levels, M(h) = M0 + C h^q with h = 1/k.

    OMP_NUM_THREADS=1 python benchmarks/calculix_check.py [--levels 1 2 3] [--probes 2 6]

Needs ``ccx`` on PATH (Debian, Ubuntu: ``apt-get install calculix-ccx``).
"""

import argparse
import os
import tempfile
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from scipy.optimize import brentq  # noqa: E402

from skinsuction.model import Skin, SuctionTest  # noqa: E402
from skinsuction.model import inp_deck, run_calculix  # noqa: E402

SKIN = Skin.two_layer(0.08, 4.1e-4)  # the reference skin: 1 + 1 mm, fixed bottom
PRESSURES = [0, 25, 50, 75, 100]
#: CalculiX on a graded mesh of its own, four halvings (the issue's figures)
KNOWN = {2.0: (0.029868, 0.030126, 0.030230, 0.030276), 6.0: (0.35872, 0.36011, 0.36092, 0.36146)}


def richardson(levels, values):
    """Mesh limit M0 and order q of M(h) = M0 + C h^q through the last three
    (level, M) pairs, h = 1/level; (nan, nan) if they are not monotone."""
    if len(levels) < 3:
        return np.nan, np.nan
    h = 1.0 / np.asarray(levels[-3:], float)
    m = np.asarray(values[-3:], float)
    ratio = (m[0] - m[1]) / (m[1] - m[2])
    if not ratio > 0:
        return np.nan, np.nan

    def gap(q):
        return (h[0] ** q - h[1] ** q) / (h[1] ** q - h[2] ** q) - ratio

    try:
        q = brentq(gap, 0.05, 6.0)
    except ValueError:
        return np.nan, np.nan
    c = (m[1] - m[2]) / (h[1] ** q - h[2] ** q)
    return m[2] - c * h[2] ** q, q


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--levels", type=int, nargs="+", default=[1, 2, 3])
    parser.add_argument("--probes", type=float, nargs="+", default=[2.0, 6.0])
    parser.add_argument("--max-increment", type=float, default=25.0,
                        help="largest CalculiX load increment, mbar (default 25)")
    args = parser.parse_args()
    print(f"{'probe':>5} {'level':>5} {'DOFs':>6} {'this model':>11} {'wall on':>9} "
          f"{'CalculiX':>11} {'difference':>10} {'s (model)':>9} {'s (ccx)':>8}")
    limits = {}
    for probe in args.probes:
        ours, theirs = [], []
        for level in args.levels:
            mesh = {"refinement": level, "probe_wall": False}
            model = SuctionTest(SKIN, probe, mesh)
            curve = model.run(PRESSURES)
            walled = SuctionTest(SKIN, probe, {**mesh, "probe_wall": True}).run(PRESSURES)
            deck = inp_deck(SuctionTest(SKIN, probe, mesh), PRESSURES,
                            max_increment_mbar=args.max_increment)
            start = time.perf_counter()
            with tempfile.TemporaryDirectory() as workdir:
                _, m_ccx = run_calculix(deck, workdir, pressures_mbar=[100.0])
            seconds = time.perf_counter() - start
            m, m_wall = curve.deflection_mm[-1], walled.deflection_mm[-1]
            ours.append(m)
            theirs.append(m_ccx[0])
            print(f"{probe:>5g} {level:>5d} {curve.dofs:>6d} {m:>11.6f} {m_wall:>9.6f} "
                  f"{m_ccx[0]:>11.6f} {(m_ccx[0] / m - 1) * 100:>+9.4f}% "
                  f"{curve.seconds:>9.1f} {seconds:>8.1f}", flush=True)
        limits[probe] = [richardson(args.levels, ours), richardson(args.levels, theirs)]
    print()
    print("Mesh limit (Richardson, last three levels): M0 mm (order q)")
    for probe, ((m0, q0), (m1, q1)) in limits.items():
        print(f"  {probe:g} mm: this model {m0:.6f} ({q0:.2f}); CalculiX {m1:.6f} ({q1:.2f}); "
              f"difference {(m1 / m0 - 1) * 100:+.4f} %")
        if probe in KNOWN:
            m2, q2 = richardson([1, 2, 4, 8], KNOWN[probe])
            print(f"        CalculiX on its own graded mesh, four halvings "
                  f"({', '.join(f'{v:g}' for v in KNOWN[probe])}): {m2:.6f} ({q2:.2f}), "
                  f"{(m2 / m0 - 1) * 100:+.2f} % from this model's limit")


if __name__ == "__main__":
    main()
