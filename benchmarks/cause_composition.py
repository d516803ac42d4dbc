"""Do two elastic causes compose additively in log M? (prints figures; asserts nothing)

For a ramp diagnosis that names two causes at once, the cheapest space would compose
the single-cause spaces: ``log M(c1, c2) = log M(c1) + log M(c2) - log M(0)``.  This
compares that with direct FE solves of the pair: X1d 0.05 MPa, X1h/X1d 0.05, 0-100 mbar
in 10 mbar steps, 2 and 6 mm probes, the default mesh; five pairs of stiffening
(X2d/X1d), pre-tension (lambda0) and the thicknesses.  Prints the largest relative
error of the composition over the ramp, beside each cause's own effect and the pair's.

    OMP_NUM_THREADS=1 python benchmarks/cause_composition.py
"""

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from skinsuction.model import Probe, Skin, simulate  # noqa: E402

P = np.arange(0.0, 101.0, 10.0)
PAIRS = [({"k": 10}, {"lam": 1.1}), ({"k": 10}, {"th": 3.0}), ({"lam": 1.1}, {"th": 3.0}),
         ({"k": 30}, {"td": 1.5}), ({"lam": 1.15}, {"td": 0.7})]


def deflection(probe, k=0.0, lam=1.0, td=1.0, th=1.0):
    x1d = 0.05
    skin = Skin.two_layer(x1d, 0.05 * x1d, x2d=k * x1d, prestretch=lam, t_d=td, t_h=th)
    return np.asarray(simulate(skin, Probe(probe), pressures_mbar=P).deflection_mm, float)[1:]


def main():
    print("| probe | pair | composition off by | cause 1, cause 2 alone | the pair |")
    print("|---|---|---|---|---|")
    for probe in (2.0, 6.0):
        m0 = deflection(probe)
        for a, b in PAIRS:
            ma, mb, mab = deflection(probe, **a), deflection(probe, **b), deflection(probe, **a, **b)
            composed = ma * mb / m0
            off = 100 * np.max(np.abs(composed / mab - 1))
            ea, eb = (100 * np.max(np.abs(m / m0 - 1)) for m in (ma, mb))
            pair = 100 * np.max(np.abs(mab / m0 - 1))
            print(f"| {probe:g} mm | {a} + {b} | {off:.2f} % | {ea:.1f} %, {eb:.1f} % | {pair:.1f} % |")


if __name__ == "__main__":
    main()
