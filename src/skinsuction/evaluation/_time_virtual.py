"""FE virtual time-curve experiments: the two-layer viscoelastic FE time solve
(:func:`skinsuction.viscoelastic.simulate_history`, independent of the fast path)
sampled as a Cutometer reads, with noise and the 0.01 mm rounding.

Used by ``tests/test_time_identify.py`` and ``benchmarks/time_identify.py``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from skinsuction._files import atomic_output

__all__ = ["mode1_suction", "mode2_suction", "virtual_curve", "virtual_skin_curve",
           "write_time_csv"]


def mode1_suction(level_mbar=400.0, on_s=3.0, off_s=2.0, cycles=2, before_s=0.5, rise_s=0.01):
    """``(p(t), switch times)``: mode 1, each switch a linear ramp of ``rise_s``
    starting at a switch time (put them on the sampling clock: the sampled suction is
    then exactly the one the FE solves)."""
    starts = [before_s + k * (on_s + off_s) for k in range(cycles)]

    def p(t):
        t = np.asarray(t, dtype=float)
        out = np.zeros_like(t)
        for s in starts:
            out += level_mbar * (np.clip((t - s) / rise_s, 0, 1)
                                 - np.clip((t - s - on_s) / rise_s, 0, 1))
        return out

    switches = [s + x for s in starts for x in (0.0, on_s)]
    return p, switches, before_s + cycles * (on_s + off_s)


def mode2_suction(peak_mbar=400.0, rate_mbar_s=100.0, before_s=0.5, after_s=1.0):
    """``(p(t), kinks, duration)``: a ramp up and down at ``rate_mbar_s``."""
    ramp = peak_mbar / rate_mbar_s

    def p(t):
        t = np.asarray(t, dtype=float) - before_s
        return np.clip(np.minimum(t, 2 * ramp - t) * rate_mbar_s, 0.0, None)

    return p, [before_s, before_s + ramp, before_s + 2 * ramp], before_s + 2 * ramp + after_s


def virtual_curve(x1d, x1h, prony, suction, *, probe_mm=6.0, rate_hz=100.0, noise_mm=0.003,
                  resolution_mm=0.01, seed=0, mesh=None):
    """``(t, p, d, exact, history)``: one FE time solve of the paper's two layers
    sharing one spectrum, sampled at ``rate_hz`` (:func:`virtual_skin_curve`)."""
    from skinsuction.model import Skin

    return virtual_skin_curve(Skin.two_layer(x1d, x1h, spectrum=prony), suction,
                              probe_mm=probe_mm, rate_hz=rate_hz, noise_mm=noise_mm,
                              resolution_mm=resolution_mm, seed=seed, mesh=mesh)


def virtual_skin_curve(skin, suction, *, probe_mm=6.0, rate_hz=100.0, noise_mm=0.003,
                       resolution_mm=0.01, seed=0, mesh=None):
    """``(t, p, d, exact, history)``: one FE time solve of any skin sampled at ``rate_hz``.

    The FE steps at every sample and at graded steps (1 ms, doubling) after each
    switch; the deflection gets Gaussian noise of ``noise_mm`` (``seed``) and is
    rounded to ``resolution_mm`` (0: neither); the suction is written to 1 mbar.

    Parameters
    ----------
    skin : skinsuction.model.Skin
        Any stack, with X2, pre-stretch and a spectrum per layer.
    suction : tuple
        ``(p(t), switch times, duration)`` (:func:`mode1_suction`, :func:`mode2_suction`).
    probe_mm, rate_hz, noise_mm, resolution_mm, seed, mesh
        The probe, the sampling, the noise and rounding, the FE mesh.

    Returns
    -------
    tuple
        ``(t, p, d, exact, history)``: samples, suction, measured and exact
        deflections (mm), the FE :class:`~skinsuction.viscoelastic.History`.

    Raises
    ------
    RuntimeError
        If the FE time solve stops.
    """
    from skinsuction.viscoelastic import simulate_history

    p_of, switches, duration = suction
    dt = 1.0 / rate_hz
    t = np.round(np.arange(0.0, duration + dt / 2, dt), 9)
    fine = [s + 1e-3 * 2.0 ** k for s in switches for k in range(6)]
    tf = np.unique(np.round(np.concatenate([t, fine]), 9))
    h = simulate_history(skin, tf, p_of(tf), probe=probe_mm, mesh=mesh)
    if not h.converged:
        raise RuntimeError(f"FE time solve stopped: {h.reason}")
    exact = np.interp(t, tf, h.deflection_mm)
    d = exact
    if noise_mm:
        d = exact + np.random.default_rng(seed).normal(0.0, noise_mm, t.size)
    if resolution_mm:
        d = np.round(d / resolution_mm) * resolution_mm
    return t, np.round(p_of(t)), d, exact, h


def write_time_csv(path, curves, header=()):
    """Write ``[(probe_mm, t, p, d), ...]`` as a time-curve CSV (atomically)."""
    lines = [f"# {h}" for h in header] + ["probe_mm,time_s,pressure_mbar,deflection_mm"]
    for probe, t, p, d in curves:
        lines += [f"{probe:g},{a:.4f},{b:.0f},{c:.4f}" for a, b, c in zip(t, p, d)]
    path = Path(path)
    with atomic_output(path) as tmp:
        tmp.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path
