"""The figures of the viscoelastic verification table (docs/viscoelasticity.md).

The same cases as ``tests/test_viscoelastic.py`` (coarse mesh, refinement 0.5),
printing the errors the tests bound: g = 0 against the elastic model, the slow
and fast limits, the creep limit, and the order of convergence in the time step.

    OMP_NUM_THREADS=1 python benchmarks/viscoelastic_verification.py
"""

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from skinsuction.model import Skin, simulate  # noqa: E402
from skinsuction.viscoelastic import Prony, graded_steps, simulate_history  # noqa: E402

COARSE = {"refinement": 0.5}
X1D, X1H = 0.08, 4.1e-3
SPECTRUM = Prony([0.5, 0.3], [0.01, 0.5])
P = np.arange(0.0, 81.0, 4.0)


def rel(a, b):
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


def main():
    el = simulate(Skin.two_layer(X1D, X1H), pressures_mbar=P, mesh=COARSE)
    f = SPECTRUM.instantaneous_factor
    inst = simulate(Skin.two_layer(X1D * f, X1H * f), pressures_mbar=P, mesh=COARSE)
    print(f"X1d {X1D}, X1h {X1H} MPa, g {SPECTRUM.g}, tau {SPECTRUM.tau_s} s, 0-80 mbar, "
          f"{el.dofs} DOFs; M(80 mbar) long-time {el.deflection_mm[-1]:.5f} mm, "
          f"instantaneous {inst.deflection_mm[-1]:.5f} mm")
    times = np.arange(2 * len(P) - 1) * 0.01
    h = simulate_history(Skin.two_layer(X1D, X1H, spectrum=None), times, np.concatenate([P, P[-2::-1]]), mesh=COARSE)
    print(f"g = 0, up: {rel(h.deflection_mm[:len(P)], el.deflection_mm):.1e}, down: "
          f"{rel(h.deflection_mm[len(P) - 1:][::-1], el.deflection_mm):.1e}")
    for T in (1e3, 1e4):
        h = simulate_history(Skin.two_layer(X1D, X1H, spectrum=SPECTRUM), P / P[-1] * T, P, mesh=COARSE)
        print(f"slow ramp over {T:g} s (tau_max/T = {0.5 / T:.0e}): {rel(h.deflection_mm, el.deflection_mm):.2e}")
    for T in (1e-4, 1e-5):
        h = simulate_history(Skin.two_layer(X1D, X1H, spectrum=SPECTRUM), P / P[-1] * T, P, mesh=COARSE)
        print(f"fast ramp over {T:g} s (T/tau_min = {T / 0.01:.0e}): {rel(h.deflection_mm, inst.deflection_mm):.2e}")
    lam = SPECTRUM.retardation()[1].max()
    t = np.concatenate([[0.0], 1e-5 + np.concatenate([[0.0], graded_steps(20 * lam, 1e-4, 1.3, 0.2)])])
    p = np.where(t > 0, P[-1], 0.0)
    h = simulate_history(Skin.two_layer(X1D, X1H, spectrum=SPECTRUM), t, p, mesh=COARSE)
    m = h.deflection_mm
    print(f"creep: step of 10 µs to 80 mbar held {20 * lam:.2f} s (20 lambda_max): start / "
          f"instantaneous - 1 = {m[1] / inst.deflection_mm[-1] - 1:.1e}, end / long-time - 1 = "
          f"{m[-1] / el.deflection_mm[-1] - 1:.1e}, smallest increment {np.diff(m[1:]).min():.1e} mm")
    spectrum = Prony([0.5, 1.0], [0.03, 0.1])
    for branches in ("full", "isochoric"):
        def run(n):
            t = np.arange(3 * n + 1) * (0.1 / n)
            return simulate_history(Skin.two_layer(X1D, X1H, spectrum=spectrum), t, np.minimum(t / 0.1, 1) * 80, mesh=COARSE, tol=1e-10, branches=branches).deflection_mm
        ref = run(128)
        errors = [np.max(np.abs(run(n) - ref[:: 128 // n])) for n in (4, 8, 16)]
        orders = np.log2(np.array(errors[:-1]) / errors[1:])
        print(f"order ({branches}): errors {', '.join(f'{1e3 * e:.2e} µm' for e in errors)} "
              f"(dt = 25, 12.5, 6.25 ms against 0.78 ms; M {1e3 * ref[-1]:.1f} µm), orders {orders.round(2).tolist()}")


if __name__ == "__main__":
    main()
