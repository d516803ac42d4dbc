"""The first load axis, for side-by-side accuracy tables: cubic Lagrange of M in q.

Until 28 November 2026 a ray was read along its load by cubic Lagrange of M in
q = p X1d_ref / X1d over every load (M(0) = 0), where it is now log M in log q
(skinsuction.space.LoadAxis). The benchmarks read the same combined rays both ways
against the same FE runs; a stencil that holds a stopped ray gives NaN here
(today's shifted stencils are left out: those pressures are not compared).
"""

from __future__ import annotations

import math

import numpy as np


def read_m_in_q(space, point, pressures) -> list:
    """The space's curve at ``point`` (an AccuracyPoint) read with the first load axis."""
    from skinsuction.space import LagrangeAxis, interpolant, reference_pressure, space_causes

    p = np.asarray(pressures, dtype=float)
    if not p.size:
        return []
    f = interpolant(space, point.probe_mm, p)
    theta = [math.log10(point.x1d), math.log10(point.ratio)]
    for cause, c in zip(space_causes(space), (point.coordinate, point.coordinate2)):
        theta.append(cause.to_axis(c))
    ray = f.combined_rays(np.array([theta]))[0]
    axis = LagrangeAxis(np.asarray(space.spec.pressures_mbar, dtype=float))
    q = reference_pressure(p, point.x1d, space.spec.x1d_ref)
    start, w = axis.weights(q)
    nodes = ray[start[:, None] + np.arange(axis.m)]
    return np.where(w == 0.0, 0.0, w * nodes).sum(axis=1).tolist()

