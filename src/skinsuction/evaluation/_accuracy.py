"""Accuracy of the scale-free space: direct FE runs against the interpolated space.

:func:`draw_points` draws random points across the whole domain of a space
(every model, both probes, X1h/X1d and the cause's value over their axes, X1d
log-uniform, a pressure protocol up to 100, 300 or 500 mbar);
:func:`compare_point` runs the FE model there (same mesh and fallbacks as the
rays) and compares it with the space at every pressure.  The benchmark
``benchmarks/scale_free_accuracy.py`` prints the statistics over many points;
the tests check a few.

The target of an error: 0.2 % of M, or 0.3 µm where M is small; the
*normalised error* ``|dM| / max(0.002 M, 0.3 µm)`` is at most 1 where met.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from skinsuction.space import BASELINE
from skinsuction.space import RaySpace, interpolant, space_causes

__all__ = ["AccuracyPoint", "draw_points", "compare_point", "normalised_error",
           "REL_TARGET", "ABS_TARGET_UM", "PROTOCOLS"]

#: Target of the interpolation error: 0.2 % of M ...
REL_TARGET = 0.002
#: ... or 0.3 µm where M is small.
ABS_TARGET_UM = 0.3
#: Pressure protocols of the draws: (largest pressure, step), mbar.
PROTOCOLS = ((100.0, 2.0), (300.0, 5.0), (500.0, 10.0))


@dataclass(frozen=True)
class AccuracyPoint:
    """One random point of the domain: model, probe, moduli, cause value, protocol."""

    model: str
    probe_mm: float
    x1d: float
    ratio: float
    coordinate: float  # the cause's ray coordinate (NaN for the neo-Hookean model)
    p_max: float
    p_step: float
    t_d: float = 1.0  # layer thicknesses, mm
    t_h: float = 1.0
    coordinate2: float = math.nan  # a pair's second cause's coordinate

    @property
    def pressures_mbar(self) -> np.ndarray:
        return np.arange(0.0, self.p_max + 1e-9, self.p_step)


def draw_points(spaces: dict, n: int, seed=0, x1d_range=(0.005, 0.15),
                coordinate_range=None, protocols=PROTOCOLS) -> list:
    """``n`` random :class:`AccuracyPoint` across the spaces' whole domain.

    The model is drawn evenly among ``spaces``; X1h/X1d log-uniform over the
    ratio nodes, the cause's axis coordinate uniform over its nodes' span (or over
    ``coordinate_range``, (lo, hi) in the cause's coordinate, e.g. lambda0 1-1.1);
    the protocol among ``protocols`` ((p_max, step) in mbar, default
    :data:`PROTOCOLS`); X1d log-uniform in ``x1d_range`` raised to the load reach
    ``p_max / load_max``.
    """
    rng = np.random.default_rng(seed)
    names = sorted(spaces)
    out = []
    for _ in range(int(n)):
        name = names[rng.integers(len(names))]
        s = spaces[name]
        spec = s.spec
        probe = float(spec.probes_mm[rng.integers(len(spec.probes_mm))])
        lr = np.log10(spec.ratio_nodes)
        ratio = 10.0 ** rng.uniform(lr[0], lr[-1])
        coord = math.nan
        if s.cause is not None:
            u = s.cause.axis_nodes
            lo_u, hi_u = u[0], u[-1]
            if coordinate_range is not None:
                lo_u, hi_u = (s.cause.to_axis(c) for c in coordinate_range)
            coord = float(s.cause.from_axis(rng.uniform(lo_u, hi_u)))
        p_max, p_step = protocols[rng.integers(len(protocols))]
        lo = max(x1d_range[0], p_max / spec.load_max)
        hi = max(lo * 1.0001, x1d_range[1])
        x1d = 10.0 ** rng.uniform(math.log10(lo), math.log10(hi))
        out.append(AccuracyPoint(name, probe, float(x1d), float(ratio), coord, p_max, p_step))
    return out


def normalised_error(fe_mm, space_mm) -> np.ndarray:
    """``|dM| / max(0.002 M, 0.3 µm)``: at most 1 where the target is met."""
    fe = np.asarray(fe_mm, dtype=float)
    d_um = 1e3 * np.abs(np.asarray(space_mm, dtype=float) - fe)
    return d_um / np.maximum(REL_TARGET * 1e3 * np.abs(fe), ABS_TARGET_UM)


def _model_keywords(space: RaySpace, point: AccuracyPoint) -> dict:
    kw = {"x1d": point.x1d, "x1h": point.x1d * point.ratio, "probe_mm": point.probe_mm,
          "bottom": space.spec.bottom}
    if (point.t_d, point.t_h) != (1.0, 1.0):
        kw.update(t_d=point.t_d, t_h=point.t_h)
    for cause, c in zip(space_causes(space), (point.coordinate, point.coordinate2)):
        kw.update(cause.simulate_keywords(c, point.x1d))
    return kw


def compare_point(space: RaySpace, point: AccuracyPoint) -> dict:
    """Direct FE run at ``point`` (the rays' mesh and fallbacks) against the space.

    Returns a JSON-able record: the point, the FE outcome, and per pressure
    (p > 0) the FE and interpolated deflections, with the error statistics over
    the pressures where both exist.
    """
    from skinsuction.space import solve_with_fallbacks

    p = point.pressures_mbar
    curve, kept, _ = solve_with_fallbacks(_model_keywords(space, point), p, space.spec.mesh,
                                          list(space.spec.fallback),
                                          label=f"accuracy point {point}", splice=True)
    fe = np.asarray(curve.deflection_mm, dtype=float).copy()
    if not curve.converged:
        fe[~(p <= curve.last_converged_mbar)] = np.nan
    f = interpolant(space, point.probe_mm, p)
    theta = [math.log10(point.x1d), math.log10(point.ratio)]
    for cause, c in zip(space_causes(space), (point.coordinate, point.coordinate2)):
        theta.append(cause.to_axis(c))
    interp = f([theta])[0]
    pos = p > 0
    both = pos & np.isfinite(fe) & np.isfinite(interp)
    err = normalised_error(fe[both], interp[both])
    rel = np.abs(interp[both] - fe[both]) / np.abs(fe[both])
    abs_um = 1e3 * np.abs(interp[both] - fe[both])
    return {
        **asdict(point), "fe_converged": bool(curve.converged),
        "fe_last_mbar": float(curve.last_converged_mbar), "fe_fallback": int(kept),
        "fe_seconds": float(curve.seconds or 0.0),
        "n_compared": int(both.sum()),
        "n_fe_only": int((pos & np.isfinite(fe) & ~np.isfinite(interp)).sum()),
        "n_space_only": int((pos & ~np.isfinite(fe) & np.isfinite(interp)).sum()),
        "max_normalised_error": float(err.max()) if err.size else math.nan,
        "max_relative_error": float(rel.max()) if rel.size else math.nan,
        "max_abs_error_um": float(abs_um.max()) if abs_um.size else math.nan,
        "m_max_mm": float(np.nanmax(fe)) if np.isfinite(fe).any() else math.nan,
        "pressure_mbar": p[both].tolist(), "fe_mm": fe[both].tolist(),
        "space_mm": interp[both].tolist(),
        "is_baseline": point.model == BASELINE,
    }
