"""Rays read first and solved only where a fit shows they matter (:class:`DeferredRays`)."""

from __future__ import annotations

import copy

from ._on_demand import OnDemandRays

__all__ = ["DeferredRays"]


class DeferredRays(OnDemandRays):
    """An :class:`OnDemandRays` that defers its solves: a ray read off the geometry
    spaces with an error estimate over the tolerance is taken from the cache if it
    was solved before, else kept as read and listed in :attr:`deferred`.

    For fits that only may matter: a diagnosis fits each cause with these rays
    first and solves them (the solver it was made from) only where the cause's fit
    lies near a value that could change the verdict
    (:data:`skinsuction.diagnose.Settings.cause_rays_margin_bic`).  A geometry
    outside a space's grid is still solved whole: there is nothing to read.

    Attributes
    ----------
    deferred : list of dict
        One per ray set read beyond the tolerance: ``cause`` (its name, None for
        the neo-Hookean rays), ``t_d_over_a``, ``t_h_over_a``, ``coordinate`` (the
        cause's node), ``rays`` and ``largest_error_estimate``.

    Examples
    --------
    >>> from skinsuction.space import (BASELINE, DeferredRays, OnDemandRays, read_ray_spaces,
    ...                                resolve_space)
    >>> spec = read_ray_spaces(resolve_space().path)[BASELINE].spec
    >>> solver = OnDemandRays(spec, progress=None)
    >>> deferring = DeferredRays.of(solver)
    >>> deferring.tolerance == solver.tolerance, deferring.deferred
    (True, [])
    """

    deferred: list

    @classmethod
    def of(cls, solver):
        """A deferring copy of ``solver`` (same specification, cache, spaces and
        tolerance); None where it has no geometry space (every ray is solved: there is
        nothing to read first).  A solver of another kind gives its own view, its
        ``deferring()``, if it has one (else None)."""
        if not isinstance(solver, OnDemandRays):
            own = getattr(solver, "deferring", None)
            return own() if callable(own) else None
        if solver.geometry is None:
            return None
        out = copy.copy(solver)
        out.__class__ = cls
        out.deferred, out.solved, out.interpolated = [], 0, 0
        return out

    def _settle(self, ref, a, cause, c, nodes, m, rows, info):
        cached = self._read_cache(ref, a, cause, c, nodes, solve=False)
        if cached is not None:  # solved before (by the strict solver, or another subject)
            m[rows] = cached[0]
            info.update(cache=cached[1]["cache"])
            return
        self.deferred.append({
            "cause": getattr(cause, "name", None), "t_d_over_a": ref.get("dermis.thickness"),
            "t_h_over_a": ref.get("hypodermis.thickness"), "coordinate": c,
            "rays": len(nodes), "largest_error_estimate": info["largest_error_estimate"]})
        info.update(rays_deferred=len(nodes), rays_solved=0,
                    rays_interpolated=info["rays_interpolated"] + len(nodes))
