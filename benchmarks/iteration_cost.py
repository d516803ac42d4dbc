"""What one Newton iteration costs, FElupe's path against the fast path (prints).

On the tangent of a real ray (6 mm probe, X1h/X1d = 0.0102, dermis 2.2 mm; or
``--probe``, ``--td``), solved to ``--pressure`` mbar and left there, both engines
of :class:`skinsuction.model.SuctionTest` are timed in the same run, each figure
the median of ``--repeats`` calls:

* the residual (FElupe: ``fem.tools.fun`` of the solid, the suction and the wall);
* the tangent's assembly into the free-DOF matrix (FElupe: ``fem.tools.jac`` and
  ``K[dof1][:, dof1]`` in the kept order; fast: straight into the CSC data);
* its factorisation: SuperLU in the kept order (both), QDLDL with its symbolic
  factorisation kept (fast, the default);
* one solve with the factors.

    python benchmarks/iteration_cost.py [--probe 6] [--td 2.2] [--repeats 30]
"""

import argparse
import time

import felupe as fem
import numpy as np
from scipy.sparse.linalg import splu

from skinsuction.model import Skin, SuctionTest
from skinsuction.model._fast import _SUPERLU_OPTIONS


def median_ms(call, repeats):
    call()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return 1e3 * float(np.median(times))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--probe", type=float, default=6.0)
    parser.add_argument("--td", type=float, default=2.2)
    parser.add_argument("--ratio", type=float, default=0.0102)
    parser.add_argument("--pressure", type=float, default=60.0, help="mbar at X1d = 0.01 MPa")
    parser.add_argument("--repeats", type=int, default=30)
    args = parser.parse_args()

    models = {}
    for engine in ("felupe", "fast"):
        m = SuctionTest(Skin.two_layer(0.01, 0.01 * args.ratio, t_d=args.td), probe=args.probe, mesh={"engine": engine})
        m.run(np.linspace(0.0, args.pressure, 16))
        models[engine] = m
    old, new = models["felupe"], models["fast"]
    n = len(new.dof1)
    b = np.ones(n)
    print(f"probe {args.probe:g} mm, t_d {args.td:g} mm, X1h/X1d {args.ratio:g}, "
          f"{n} free DOFs, {new.mesh.ncells} cells, at {args.pressure:g} mbar; "
          f"median of {args.repeats} calls, ms")

    rows = {}
    rows["residual"] = (median_ms(old._residual, args.repeats),
                        median_ms(new._residual, args.repeats))

    def felupe_assembly():
        K = fem.tools.jac(old.items, old.field).tocsr()
        rows_ = old._factorize._rows
        return K[rows_][:, rows_].tocsc()

    old._tangent()  # the kept order
    u = new.field[0].values
    rows["tangent assembly (free DOFs)"] = (
        median_ms(felupe_assembly, args.repeats),
        median_ms(lambda: new.fast.tangent(u, new._pressure), args.repeats))
    A_old = felupe_assembly()
    data = new.fast.tangent(u, new._pressure)
    A_new = new.fast.matrix(data)
    superlu_old = median_ms(lambda: splu(A_old, permc_spec="NATURAL",
                                         options=_SUPERLU_OPTIONS), args.repeats)
    superlu_new = median_ms(lambda: splu(A_new, permc_spec="NATURAL",
                                         options=_SUPERLU_OPTIONS), args.repeats)
    rows["factorisation, SuperLU in the kept order"] = (superlu_old, superlu_new)
    new.fast.solver = "qdldl"
    rows["factorisation, QDLDL (fast default)"] = (
        float("nan"), median_ms(lambda: new.fast.factorize(data), args.repeats))
    lu_old = old._factorize(fem.tools.jac(old.items, old.field))
    lu_new = new.fast.factorize(data)
    rows["solve"] = (median_ms(lambda: lu_old.solve(b), args.repeats),
                     median_ms(lambda: lu_new.solve(b), args.repeats))

    print(f"{'':44s} {'FElupe':>9s} {'fast':>9s} {'ratio':>7s}")
    for name, (t_old, t_new) in rows.items():
        print(f"{name:44s} {t_old:9.2f} {t_new:9.2f} {t_old / t_new:7.1f}")
    full_old = rows["residual"][0] + rows["tangent assembly (free DOFs)"][0] + superlu_old \
        + rows["solve"][0]
    full_new = rows["residual"][1] + rows["tangent assembly (free DOFs)"][1] \
        + rows["factorisation, QDLDL (fast default)"][1] + rows["solve"][1]
    print(f"{'a full Newton iteration (residual, tangent, factors, solve)':44s} "
          f"{full_old:9.2f} {full_new:9.2f} {full_old / full_new:7.1f}")
    modified_old = rows["residual"][0] + rows["solve"][0]
    modified_new = rows["residual"][1] + rows["solve"][1]
    print(f"{'an iteration with kept factors':44s} {modified_old:9.2f} {modified_new:9.2f} "
          f"{modified_old / modified_new:7.1f}")


if __name__ == "__main__":
    main()
