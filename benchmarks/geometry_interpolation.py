"""Could a precomputed grid over the geometry (t_d/a, t_h/a) replace rays on demand?

    python benchmarks/geometry_interpolation.py RATIO_TD RATIO_TH
    python benchmarks/geometry_interpolation.py 1.626 1.728   # 8 x 9 nodes over the domain
    python benchmarks/geometry_interpolation.py 1.3 1.45

Cubic Lagrange interpolation of log M across geometry nodes spaced by a constant
ratio, against direct FE runs halfway between nodes (2 mm probe, so t = t/a in
mm; X1d = 0.01 MPa, loads to p/X1d = 20 000 mbar/MPa): along t_d/a around 0.33
(t_h/a = 0.6) and along t_h/a around 0.6 (t_d/a = 0.33), for X1h/X1d = 0.003,
0.03, 0.3 and 2. Prints the largest and the median relative error over the
loads of the two midpoints. The answer (docs/geometry.md): under a soft
hypodermis M changes fourfold between t_d/a = 0.2 and 0.55, and nodes 1.3 apart
still miss by 1.1 %; the space's 0.2 % would take some 24 nodes in t_d/a times
11 in t_h/a times 16 in X1h/X1d. Asserts nothing.
"""

import sys

import numpy as np

from skinsuction.model import Skin, simulate
from skinsuction.space import LagrangeAxis

P = np.linspace(0, 200, 21)


def deflection(td, th, r):
    c = simulate(Skin.two_layer(0.01, 0.01 * r, t_d=td, t_h=th), probe=2, pressures_mbar=P)
    m = np.full(P.size, np.nan)
    d = np.asarray(c.deflection_mm)
    m[:d.size] = d
    if not c.converged:
        m[P > c.last_converged_mbar] = np.nan
    return m


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    ratio_d, ratio_h = (float(x) for x in argv[:2]) if len(argv) >= 2 else (1.626, 1.728)
    for r in (0.003, 0.03, 0.3, 2.0):
        for axis, base, rat in (("t_h/a", 0.6, ratio_h), ("t_d/a", 0.33, ratio_d)):
            nodes = base * rat ** np.arange(-2, 3)
            at = (lambda x: deflection(x, 0.6, r)) if axis == "t_d/a" else \
                (lambda x: deflection(0.33, x, r))
            vals = np.array([at(n) for n in nodes])
            ax = LagrangeAxis(np.log10(nodes))
            errs = []
            for x in (base * rat ** -0.5, base * rat ** 0.5):
                s, w = ax.weights([np.log10(x)])
                est = np.exp(np.einsum("k,kp->p", w[0], np.log(vals[s[0]:s[0] + 4, 1:])))
                errs.append(np.abs(est / at(x)[1:] - 1))
            e = np.concatenate(errs)
            print(f"X1h/X1d = {r:g}, along {axis}, nodes {rat:g} apart: largest error "
                  f"{100 * np.nanmax(e):.3f} %, median {100 * np.nanmedian(e):.3f} %", flush=True)


if __name__ == "__main__":
    main()
