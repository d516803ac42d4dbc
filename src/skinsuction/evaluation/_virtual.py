"""Virtual experiments: FE suction curves with a hidden effect and measurement noise.

Used for the shipped example (``data/example_suction_synthetic.csv``), the
hidden-effect tests and the confusion-matrix benchmark.  Every curve is a
direct FE run of :func:`skinsuction.model.simulate` (never read from a
simulated space), with Gaussian noise on every deflection at p > 0 (the
Cutometer zeroes at p = 0), drawn from a seed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from skinsuction.space import NONE, Cause

__all__ = ["VirtualExperiment", "virtual_experiment", "draw_experiment", "write_csv",
           "DRAW_RANGES", "DETECTABLE_EFFECTS"]

#: Ranges of the random draws of the hidden-effect tests and the confusion benchmark:
#: where the effects are detectable.  They change the shape of M(p) only where the
#: skin deforms a lot (soft dermis, much softer hypodermis: 6 mm deflection at
#: 100 mbar of 0.6-1.2 mm); at X1d = 0.04 MPa and X1h / X1d = 0.03 the neo-Hookean
#: model absorbs X2d / X1d = 4, t_d = 1.6 mm or lambda0 = 1.06 in its two moduli to
#: better than 0.5 µm RMS.  X1d and X1h / X1d are drawn log-uniform, the noise sd
#: uniform (a Cutometer resolves about 1-10 µm).
DRAW_RANGES = {
    "x1d_mpa": (0.025, 0.035),
    "x1h_over_x1d": (0.006, 0.02),
    "noise_um": (1.0, 2.5),
}

#: Effect sizes of the draws (ray coordinates: X2d / X1d, t_d in mm, lambda0), from
#: where the misfit they leave in the neo-Hookean fit exceeds about half the noise.
#: A cause may have several intervals (a thinner and a thicker dermis); a draw picks
#: one with equal probability.
DETECTABLE_EFFECTS = {
    "strain_stiffening": ((6.0, 14.0),),
    "dermis_thickness": ((0.65, 0.8), (1.6, 2.0)),
    "pre_tension": ((1.05, 1.11),),
}


@dataclass
class VirtualExperiment:
    """Parameters of a virtual experiment and its noisy curves."""

    x1d: float
    x1h: float
    cause: str
    value: float | None  # the hidden parameter (MPa, mm or 1); None for `none`
    keyword: str | None
    noise_um: float
    seed: int
    pressures_mbar: np.ndarray
    probes_mm: tuple
    mesh: dict
    curves: dict = field(default_factory=dict)  # (probe, replicate) -> deflection (mm)
    clean: dict = field(default_factory=dict)  # probe -> noise-free FE curve (mm)
    converged: bool = True
    replicates: int = 1
    unit: str | None = None

    @property
    def truth(self) -> dict:
        out = {"cause": self.cause, "X1d": self.x1d, "X1h": self.x1h,
               "noise_um": self.noise_um, "seed": self.seed}
        if self.keyword:
            out[self.keyword] = self.value
        return out


def virtual_experiment(x1d, x1h, cause: Cause | None = None, value=None, *, noise_um=2.0,
                       seed=0, probes_mm=(2.0, 6.0), pressures_mbar=None, mesh=None,
                       replicates: int = 1, bottom="fixed", fallback=None,
                       clean: dict | None = None, layers: dict | None = None,
                       keywords: dict | None = None) -> VirtualExperiment:
    """FE curves at (X1d, X1h) with the hidden effect ``cause = value``, plus noise.

    ``value`` is in the unit of the cause's parameter (X2d in MPa, t_d in mm,
    lambda0); ``cause=None`` is the neo-Hookean model.  ``fallback``: fallback
    meshes where the first solve stops (:func:`skinsuction.space.solve_with_fallbacks`),
    as for the rays of the space.  ``clean``: ``{probe: noise-free curve}`` of
    these parameters from an earlier run (e.g. a benchmark's cache), used instead
    of solving again; the noise is drawn from ``seed`` all the same.  ``layers``:
    ``{"t_d": mm, "t_h": mm}`` of the skin (default the paper's 1 mm each).
    ``keywords``: further keywords of the model (a second effect, e.g.
    ``{"prestretch": 1.1}``), hidden like ``cause``'s but not in ``truth``.
    """
    from skinsuction.space import solve_with_fallbacks

    p = (np.arange(0.0, 101.0, 2.0) if pressures_mbar is None
         else np.asarray(pressures_mbar, dtype=float))
    kw = {k: float(v) for k, v in {**(layers or {}), **(keywords or {})}.items()}
    if cause is not None:
        kw[cause.keyword] = float(value)
    rng = np.random.default_rng(seed)
    ve = VirtualExperiment(float(x1d), float(x1h), cause.name if cause else NONE,
                           None if cause is None else float(value),
                           None if cause is None else cause.symbol, float(noise_um), seed, p,
                           tuple(float(q) for q in probes_mm), dict(mesh or {}),
                           replicates=int(replicates), unit=None if cause is None else cause.unit)
    for probe in ve.probes_mm:
        if clean is not None:
            curve = np.asarray(clean[probe], dtype=float)
            ve.converged &= bool(np.all(np.isfinite(curve)))
        else:
            c, _, _ = solve_with_fallbacks(dict(x1d=x1d, x1h=x1h, probe_mm=probe,
                                                bottom=bottom, **kw), p, dict(mesh or {}),
                                           fallback, label=f"virtual experiment {seed}",
                                           splice=True)
            ve.converged &= bool(c.converged)
            curve = c.deflection_mm
        ve.clean[probe] = curve
        for r in range(ve.replicates):
            m = curve + rng.normal(0.0, 1e-3 * noise_um, p.size)
            m[p == 0] = 0.0
            ve.curves[(probe, r)] = m
    return ve


def draw_experiment(seed, cause: Cause | None, *, effect_range=None, ranges=None, **kw):
    """A virtual experiment with moduli, effect size and noise drawn from ``seed``.

    X1d log-uniform in ``ranges["x1d_mpa"]``, X1h / X1d log-uniform in
    ``ranges["x1h_over_x1d"]``, the noise uniform in ``ranges["noise_um"]`` and
    the hidden coordinate of the cause uniform in ``effect_range`` (ray
    coordinate: X2d / X1d, t_d or lambda0; default :data:`DETECTABLE_EFFECTS`).
    ``ranges`` default to :data:`DRAW_RANGES`.
    """
    r = {**DRAW_RANGES, **(ranges or {})}
    if cause is not None and effect_range is None:
        effect_range = DETECTABLE_EFFECTS[cause.name]
    rng = np.random.default_rng(np.random.SeedSequence(seed).spawn(1)[0])
    x1d = math.exp(rng.uniform(*np.log(r["x1d_mpa"])))
    ratio = math.exp(rng.uniform(*np.log(r["x1h_over_x1d"])))
    noise = rng.uniform(*r["noise_um"])
    value = None
    if cause is not None:
        intervals = np.atleast_2d(np.asarray(effect_range, dtype=float))
        lo, hi = intervals[rng.integers(len(intervals))]
        coord = rng.uniform(lo, hi)
        value = cause.value(coord, x1d)
    return virtual_experiment(x1d, ratio * x1d, cause, value, noise_um=noise, seed=seed, **kw)


def write_csv(ve: VirtualExperiment, path, header=()) -> Path:
    """Write the experiment in the measured-CSV format, labelled as synthetic."""
    from skinsuction._files import atomic_output

    lines = ["# SYNTHETIC VIRTUAL EXPERIMENT, NOT A MEASUREMENT (skinsuction FE model + noise)",
             *(f"# {h}" for h in header)]
    truth = ve.truth
    lines += [f"# true_cause: {truth['cause']}", f"# true_x1d_mpa: {ve.x1d:.6g}",
              f"# true_x1h_mpa: {ve.x1h:.6g}"]
    if ve.keyword:
        unit = {"MPa": "_mpa", "mm": "_mm"}.get(ve.unit or "", "")
        lines.append(f"# true_{ve.keyword.lower()}{unit}: {ve.value:.6g}")
    lines += [f"# noise_sd_um: {ve.noise_um:.6g}", f"# noise_seed: {ve.seed}",
              f"# mesh: {ve.mesh}"]
    rep = ve.replicates > 1
    lines.append("probe_mm,pressure_mbar,deflection_mm" + (",curve" if rep else ""))
    for (probe, r), m in sorted(ve.curves.items()):
        for p, x in zip(ve.pressures_mbar, m):
            lines.append(f"{probe:g},{p:g},{x:.5f}" + (f",R{r + 1}" if rep else ""))
    with atomic_output(path) as tmp:
        tmp.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return Path(path)
