"""Speed and accuracy of the forward model (prints figures; asserts nothing).

For the reference case (X1d = 0.08 MPa, X1h = 4.1e-4 MPa, fixed bottom) and both
probes: DOFs, Newton iterations, seconds per 51-point curve on one core, and the
error of M(100 mbar) against nested refinements of the default mesh (and their
Richardson extrapolation). Beside it, in the same run, the same mesh solved with
FElupe's plain ``newtonraphson`` (default solver and check) per pressure step, and
our solver on FElupe's assembly (``engine="felupe"``) instead of the fast path.

    OMP_NUM_THREADS=1 python benchmarks/forward_speed.py [--levels 3] [--repeats 3]
"""

import argparse
import os
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import felupe as fem  # noqa: E402
import numpy as np  # noqa: E402

from skinsuction.model import MBAR_TO_MPA, Skin, SuctionTest  # noqa: E402

REFERENCE = Skin.two_layer(0.08, 4.1e-4)
PRESSURES = np.arange(0.0, 101.0, 2.0)


def timed_curve(probe, mesh=None, repeats=1):
    best = None
    for _ in range(repeats):
        model = SuctionTest(REFERENCE, probe, mesh=mesh)
        start = time.perf_counter()
        curve = model.run(PRESSURES)
        seconds = time.perf_counter() - start
        best = seconds if best is None else min(best, seconds)
    return model, curve, best


def felupe_plain_newton(probe):
    """Same mesh and items, FElupe's newtonraphson with its defaults per step."""
    model = SuctionTest(REFERENCE, probe)
    start = time.perf_counter()
    iterations = 0
    for p in PRESSURES[1:]:
        model.suction.update(-p * MBAR_TO_MPA)
        res = fem.newtonraphson(
            items=model.items, x0=model.field, dof1=model.dof1, dof0=model.dof0,
            ext0=model.ext0, verbose=0,
        )
        model.field[0].values[:] = res.x[0].values
        iterations += res.iterations
    return time.perf_counter() - start, iterations, model.apex_deflection()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--levels", type=int, default=3, help="nested refinements 1..LEVELS")
    parser.add_argument("--repeats", type=int, default=3, help="timed repeats (best kept)")
    parser.add_argument("--no-baseline", action="store_true", help="skip FElupe's plain Newton")
    args = parser.parse_args()

    print(f"{'probe':>5} {'refine':>6} {'DOFs':>6} {'Newton':>6} {'s/curve':>8} {'M(100) mm':>11}")
    for probe in (6, 2):
        M = []
        for level in range(1, args.levels + 1):
            model, curve, seconds = timed_curve(
                probe, {"refinement": level}, repeats=args.repeats if level == 1 else 1
            )
            M.append(curve.deflection_mm[-1])
            print(f"{probe:>5} {level:>6} {model.dofs:>6} {curve.newton_iterations:>6} "
                  f"{seconds:>8.2f} {M[-1]:>11.6f}")
        if len(M) >= 3:
            # observed order from h, h/2, h/3 and the extrapolated limit
            ratio = (M[1] - M[0]) / (M[2] - M[1])
            orders = np.linspace(0.2, 4, 3801)
            model_ratio = (1 - 2.0**-orders) / (2.0**-orders - 3.0**-orders)
            q = orders[np.argmin(abs(model_ratio - ratio))]
            C = (M[2] - M[0]) / (1 - 3.0**-q)
            limit = M[0] + C
            print(f"      observed order {q:.2f}; extrapolated M(100) = {limit:.6f} mm")
            print(f"      default-mesh error: {100 * (M[0] / limit - 1):+.2f} % against the "
                  f"extrapolation, {100 * (M[0] / M[-1] - 1):+.2f} % against the finest mesh")
        if not args.no_baseline:
            seconds, iterations, M_plain = felupe_plain_newton(probe)
            _, curve, ours = timed_curve(probe, repeats=1)
            print(f"      FElupe plain newtonraphson on the same mesh: {seconds:.2f} s, "
                  f"{iterations} iterations, M(100) = {M_plain:.6f} mm; "
                  f"ours {ours:.2f} s, {curve.newton_iterations} iterations "
                  f"(ratio {seconds / ours:.1f}x)")
            _, reference, felupe_engine = timed_curve(probe, {"engine": "felupe"}, repeats=1)
            print(f"      our solver on FElupe's assembly (engine felupe): {felupe_engine:.2f} s, "
                  f"{reference.newton_iterations} iterations, M(100) differs by "
                  f"{abs(reference.deflection_mm[-1] / curve.deflection_mm[-1] - 1):.1e} "
                  f"(the fast path {felupe_engine / ours:.1f}x faster)")


if __name__ == "__main__":
    main()
