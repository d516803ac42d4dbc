"""Virtual experiments from another discretisation or another FE code.

The simulated space is built with one discretisation (quadratic serendipity cells with
reduced quadrature, ``quad8r``, on the default graded mesh).  A measured skin is not
that discretisation: a verdict or an interval that the difference between two sound
discretisations overturns is too confident.  :data:`OTHER_SOLVERS` names the ones the
diagnosis is checked on, and :func:`solver_curves` makes a draw's noise-free curves
with one of them:

``space``
    the space's own mesh, solver and fallbacks (the reference of every benchmark);
``refined``
    every element split into four (``refinement: 2``): within 0.06 % of the mesh limit
    where the default mesh is 0.26 % off under the 2 mm probe;
``quad9``
    nine-node Lagrange cells with the full 3 x 3 rule: another element, whose
    volumetric penalty locks a little at nu = 0.49 (0.5-0.8 % stiffer on this mesh);
``felupe``
    the space's discretisation assembled by FElupe instead of the model's own fast
    path (another code path, the same equations);
``calculix``
    CalculiX (``ccx``) on the space's mesh, from :func:`skinsuction.model.inp_deck`:
    its own elements and Newton solver (no pre-stretch: pre-tension draws are refused).
"""

from __future__ import annotations

import tempfile

import numpy as np

__all__ = ["OTHER_SOLVERS", "solver_curves", "SolverRefused"]

#: name -> mesh settings over the space's own (``code``: the FE code that solves them)
OTHER_SOLVERS = {
    "space": {},
    "refined": {"mesh": {"refinement": 2}},
    "quad9": {"mesh": {"element": "quad9", "quadrature": "full"}},
    "felupe": {"mesh": {"engine": "felupe"}},
    "calculix": {"code": "calculix", "mesh": {"probe_wall": False}},
}


class SolverRefused(ValueError):
    """The solver cannot carry this draw (CalculiX and a pre-stretched skin)."""


def _solver(name: str) -> dict:
    try:
        return OTHER_SOLVERS[name]
    except KeyError:
        raise ValueError(f"unknown solver {name!r}: one of {sorted(OTHER_SOLVERS)}") from None


def solver_mesh(name: str, mesh: dict | None) -> dict:
    """The mesh settings a solver runs: the space's ``mesh`` with its overrides."""
    return {**dict(mesh or {}), **_solver(name).get("mesh", {})}


def _calculix_curve(params: dict, pressures, mesh: dict, max_increment_mbar: float):
    from skinsuction import model
    from skinsuction.model import CalculixError, SuctionTest, inp_deck, run_calculix
    from skinsuction.space import two_layer_skin

    skin, probe = two_layer_skin(model, params)
    if skin.has_prestretch:
        raise SolverRefused("CalculiX decks carry no pre-stretch (inp_deck)")
    fe = SuctionTest(skin, probe, mesh)
    with tempfile.TemporaryDirectory() as tmp:
        try:
            _, m = run_calculix(inp_deck(fe, pressures, max_increment_mbar=max_increment_mbar),
                                tmp, pressures_mbar=pressures, timeout=1800)
        except CalculixError:
            return np.full(len(pressures), np.nan)
    return np.asarray(m, dtype=float)


def solver_curves(name: str, params: dict, probes_mm, pressures_mbar, mesh: dict | None,
                  fallback=None, max_increment_mbar: float = 5.0) -> dict:
    """Noise-free M(p) of one skin under each probe, from the solver ``name``.

    Parameters
    ----------
    name : str
        A key of :data:`OTHER_SOLVERS`.
    params : dict
        The skin's keywords (:func:`skinsuction.space.two_layer_skin`: ``x1d, x1h``
        and optionally ``x2d, t_d, t_h, prestretch, bottom``).
    probes_mm : sequence of float
        The apertures.
    pressures_mbar : array_like
        The pressures, ascending from 0.
    mesh : dict
        The space's mesh settings; the solver's overrides go over them, and over each
        fallback mesh (the FE solvers splice a fallback's curve where the first stops,
        as the space does; CalculiX has none: it cuts its own increments).
    fallback : list of dict, optional
        The space's fallback meshes.
    max_increment_mbar : float
        CalculiX's largest load increment.

    Returns
    -------
    dict
        ``{probe: deflections (mm)}``, NaN where the solver did not reach a pressure.

    Raises
    ------
    SolverRefused
        Where the solver cannot carry the skin.

    Examples
    --------
    >>> m = solver_curves("refined", {"x1d": 0.08, "x1h": 4.1e-4}, [2.0], [0, 50, 100],
    ...                   {"refinement": 0.5})
    >>> bool(0.02 < m[2.0][-1] < 0.04)
    True
    """
    from skinsuction.space import solve_with_fallbacks

    p = np.asarray(pressures_mbar, dtype=float)
    spec = _solver(name)
    own = solver_mesh(name, mesh)
    out = {}
    for probe in probes_mm:
        kw = {**params, "probe_mm": float(probe)}
        if spec.get("code") == "calculix":
            out[float(probe)] = _calculix_curve(kw, p, own, max_increment_mbar)
            continue
        over = spec.get("mesh", {})
        fb = [{**dict(f), **over} for f in (fallback or [])]
        curve, _, _ = solve_with_fallbacks(kw, p, own, fb, label=f"{name} solve", splice=True)
        out[float(probe)] = np.asarray(curve.deflection_mm, dtype=float)
    return out
