"""Make the synthetic Cutometer time curves of data/ (not measurements).

An analytic linear-viscoelastic creep model, no FE and no skin: under the 6 mm probe
a suction step of 400 mbar gives the deflection

    u(t) = 0.45 + 0.10 (1 - exp(-t / 0.01 s)) + 0.20 (1 - exp(-t / 0.5 s))   mm,

an elastic jump and two Kelvin-Voigt terms (the two time constants reported for
skin, about 10 ms and 0.1-1 s).  The deflection under any suction history p(t) is
its Boltzmann superposition, ``u(t) = sum over the increments dp(s) of
dp(s) / 400 mbar * J(t - s)``, summed on a 0.1 ms grid (midpoint rule).  The pump's
suction rises and falls with a 15 ms time constant.  Sampled at 100 Hz, as a
Cutometer reads; the pressure gets Gaussian noise of sd 2 mbar and is written to
1 mbar, the deflection gets Gaussian noise of sd 3 µm and is rounded to 0.01 mm
(the Cutometer's resolution); NumPy seed 0.

* ``example_mode1.csv``: mode 1, 400 mbar, 3 s on / 2 s off, 5 cycles after 0.5 s
  off (the switches 3 ms after a sample, as a valve does not wait for the clock);
* ``example_mode2.csv``: mode 2, a ramp of 25 mbar/s up to 400 mbar and down at the
  same rate, 1 s off before and 3 s after.

    python data/make_example_timecurves.py [NAME ...]   # default: both
"""

from pathlib import Path

import numpy as np
from scipy.signal import fftconvolve

P_REF = 400.0            # mbar: the model's step
U0, A1, TAU1, A2, TAU2 = 0.45, 0.10, 0.01, 0.20, 0.5   # mm, mm, s, mm, s
TAU_PUMP = 0.015         # s
RATE_HZ = 100.0
FINE_S = 1e-4
P_NOISE_MBAR, U_NOISE_MM, RESOLUTION_MM = 2.0, 0.003, 0.01
SEED = 0
PROBE_MM = 6.0


def creep(s):
    """Deflection (mm) a time s (>= 0) after a 400 mbar step."""
    return U0 + A1 * (1 - np.exp(-s / TAU1)) + A2 * (1 - np.exp(-s / TAU2))


def mode1_pressure(t):
    """Suction (mbar) of 5 cycles of 3 s on / 2 s off, starting at 0.503 s."""
    p = np.zeros_like(t)
    for k in range(5):
        on, off = 0.503 + 5.0 * k, 3.503 + 5.0 * k
        rising = (t >= on) & (t < off)
        p[rising] = P_REF * (1 - np.exp(-(t[rising] - on) / TAU_PUMP))
        top = P_REF * (1 - np.exp(-(off - on) / TAU_PUMP))
        falling = (t >= off) & (t < on + 5.0)
        p[falling] = top * np.exp(-(t[falling] - off) / TAU_PUMP)
    return p


def mode2_pressure(t):
    """25 mbar/s up to 400 mbar from 1.003 s, then down at the same rate."""
    rate, start = 25.0, 1.003
    top = start + P_REF / rate
    return np.clip(np.where(t < top, rate * (t - start), P_REF - rate * (t - top)), 0, None)


EXAMPLES = {
    "example_mode1.csv": dict(pressure=mode1_pressure, duration=25.5,
                              protocol="mode 1, 400 mbar, 3 s on / 2 s off, 5 cycles"),
    "example_mode2.csv": dict(pressure=mode2_pressure, duration=36.0,
                              protocol="mode 2, 25 mbar/s up to 400 mbar and down"),
}


def deflection(pressure, t):
    """Boltzmann superposition of the creep on a fine grid (midpoint rule)."""
    fine = np.arange(0.0, t[-1] + 2 * FINE_S, FINE_S)
    dp = np.diff(pressure(fine))
    kernel = creep((np.arange(dp.size) + 0.5) * FINE_S)
    u = np.concatenate([[0.0], fftconvolve(dp, kernel)[:dp.size]]) / P_REF
    return np.interp(t, fine, u)


def make(out, pressure, duration, protocol):
    rng = np.random.default_rng(SEED)
    t = np.round(np.arange(0.0, duration, 1.0 / RATE_HZ), 6)
    p = np.round(pressure(t) + rng.normal(0.0, P_NOISE_MBAR, t.size))
    u = deflection(pressure, t) + rng.normal(0.0, U_NOISE_MM, t.size)
    u = RESOLUTION_MM * np.round(u / RESOLUTION_MM)
    header = [
        f"# SYNTHETIC EXAMPLE, NOT A MEASUREMENT. Made by data/make_example_timecurves.py from "
        "an analytic",
        "# linear-viscoelastic creep model (no FE, no skin), where a 400 mbar step gives u(t) = "
        "0.45 + 0.10 (1 - exp(-t/0.01 s))",
        "# + 0.20 (1 - exp(-t/0.5 s)) mm, superposed over the suction history; the pump rises "
        "and falls with 15 ms.",
        "# Sampled at 100 Hz; pressure + Gaussian noise sd 2 mbar, to 1 mbar; deflection + "
        "Gaussian noise sd 3 um,",
        "# rounded to 0.01 mm (the Cutometer's resolution); NumPy seed 0.",
        "# subject: synthetic",
        f"# protocol: {protocol}",
        "# creep_elastic_mm: 0.45",
        "# creep_kv1_mm: 0.10",
        "# creep_tau1_s: 0.01",
        "# creep_kv2_mm: 0.20",
        "# creep_tau2_s: 0.5",
        "# pressure_noise_sd_mbar: 2",
        "# deflection_noise_sd_um: 3",
        "# deflection_resolution_mm: 0.01",
        "# noise_seed: 0",
        "probe_mm,time_s,pressure_mbar,deflection_mm",
    ]
    p, u = p + 0.0, u + 0.0  # no "-0" in the file
    rows = [f"{PROBE_MM:g},{ti:.2f},{pi:.0f},{ui:.2f}" for ti, pi, ui in zip(t, p, u)]
    out.write_text("\n".join(header + rows) + "\n", encoding="utf-8")
    print(f"wrote {out} ({out.stat().st_size / 1024:.0f} kB, {t.size} samples)")


def main(*names):
    for name in names or EXAMPLES:
        make(Path(__file__).with_name(name), **EXAMPLES[name])


if __name__ == "__main__":
    import sys

    main(*sys.argv[1:])
