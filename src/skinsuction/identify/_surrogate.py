"""A smooth analytic stand-in for the FE simulated space (tests, examples, benchmarks).

Not a skin model: it only mimics the features of the FE curves that matter to
the identification -- deflections of the right size (about 1 mm at 100 mbar),
stiffening with pressure, and a hypodermis that matters much more under the
6 mm aperture than under the 2 mm one (paper, Figure 3).

    M(p) = 0.5 a (p / k) / sqrt(1 + (a / 1 mm) p / X1d),   k = X1d + (a / 1 mm)^2 X1h,

with a = probe_mm / 2 (mm) and p in MPa (1 mbar = 1e-4 MPa).  The initial
compliance sees both layers, the hypodermis more so under a wide aperture; the
stiffening sees the dermis only and depends on the aperture.  So the 6 mm curve
determines both moduli, the 2 mm curve hardly X1h, and the ratio of the two
curves (eqs. 11-12) depends on both moduli.
"""

from __future__ import annotations

import numpy as np

from skinsuction.space import GriddedSpace

__all__ = [
    "PAPER_X1D",
    "PAPER_X1H",
    "PAPER_PRESSURE_MBAR",
    "surrogate_deflection",
    "analytic_surrogate_space",
]

#: Dermis moduli of the paper's simulated space (eq. 3), MPa: 0.001, 0.010, ..., 0.091.
PAPER_X1D = 0.001 + 0.009 * np.arange(11)
#: Hypodermis moduli of the paper's simulated space (eq. 3), MPa: 1e-5, 2.1e-4, ..., 2.01e-3.
PAPER_X1H = 1e-5 + 2e-4 * np.arange(11)
#: Pressures of the paper's simulated space (eq. 3), mbar: 0, 2, ..., 100.
PAPER_PRESSURE_MBAR = np.arange(0.0, 101.0, 2.0)


def surrogate_deflection(dermis_X1, hypodermis_X1, pressure_mbar, probe_mm: float) -> np.ndarray:
    """Analytic deflection (mm) with shape ``broadcast(dermis_X1, hypodermis_X1).shape +
    (n_p,)``: a smooth stand-in for the FE model, not the physics.

    Parameters
    ----------
    dermis_X1, hypodermis_X1 : array_like
        The layers' moduli X1 (MPa), broadcast against each other.
    pressure_mbar : array_like
        Suction pressures (mbar).
    probe_mm : float
        Aperture diameter (mm).

    Returns
    -------
    ndarray

    Examples
    --------
    >>> round(float(surrogate_deflection(0.0055, 0.00041, [100.0], 6.0)[0]), 4)
    0.6425
    """
    a = 0.5 * float(probe_mm)
    p = 1e-4 * np.asarray(pressure_mbar, dtype=float)
    x1d = np.asarray(dermis_X1, dtype=float)[..., None]
    x1h = np.asarray(hypodermis_X1, dtype=float)[..., None]
    k = x1d + a**2 * x1h
    return 0.5 * a * (p / k) / np.sqrt(1.0 + a * p / x1d)


def analytic_surrogate_space(
    probe_mm: float,
    dermis_X1=PAPER_X1D,
    hypodermis_X1=PAPER_X1H,
    pressure_mbar=PAPER_PRESSURE_MBAR,
) -> GriddedSpace:
    """The surrogate tabulated on a grid (default: the paper's 11 x 11 x 51 grid).

    Parameters
    ----------
    probe_mm : float
        Aperture diameter (mm).
    dermis_X1, hypodermis_X1 : array_like
        The grid's nodes of the layers' X1 (MPa).
    pressure_mbar : array_like
        The grid's pressures (mbar).

    Returns
    -------
    GriddedSpace

    Examples
    --------
    >>> analytic_surrogate_space(2.0).shape
    (11, 11, 51)
    """
    x1d = np.asarray(dermis_X1, dtype=float)
    x1h = np.asarray(hypodermis_X1, dtype=float)
    m = surrogate_deflection(x1d[:, None], x1h[None, :], pressure_mbar, probe_mm)
    return GriddedSpace(x1d, x1h, pressure_mbar, m, probe_mm)


def surrogate_curve(skin, probe=6.0, pressures_mbar=None, mesh=None):
    """The analytic surrogate as a :class:`skinsuction.model.Curve`-like object.

    Same call as :func:`skinsuction.model.simulate`, no FE: for tests,
    examples and plumbing runs of the workflow only. Only the skin's dermis and
    hypodermis X1 act.

    Parameters
    ----------
    skin : skinsuction.model.Skin
        A skin with a dermis and a hypodermis.
    probe : float
        Aperture diameter (mm).
    pressures_mbar : array_like, optional
        Default 0, 2, ..., 100 mbar.
    mesh : dict, optional
        Recorded, not used.

    Returns
    -------
    types.SimpleNamespace
        With the fields of :class:`skinsuction.model.Curve`.
    """
    from types import SimpleNamespace

    p = np.arange(0.0, 101.0, 2.0) if pressures_mbar is None else np.asarray(pressures_mbar, float)
    m = surrogate_deflection(skin.get("dermis.X1"), skin.get("hypodermis.X1"), p, float(probe))
    return SimpleNamespace(pressure_mbar=p, deflection_mm=m, converged=True,
                           last_converged_mbar=float(p[-1]), reason="", newton_iterations=0,
                           dofs=0, seconds=0.0, info={"surrogate": True, "mesh": mesh})


def write_surrogate_space(path, dermis_X1, hypodermis_X1, pressures_mbar, probes=(2.0, 6.0), *,
                          curves_dir=None, name="surrogate") -> None:
    """A simulated-space database filled with the analytic surrogate (not the FE model).

    For tests and demonstrations of the identification without FE runs.  With
    ``curves_dir`` the curve files (one a row of the grid) are written there as well
    (as the workflow's ``results/curves``).

    Parameters
    ----------
    path : path
        The database to write.
    dermis_X1, hypodermis_X1 : sequence of float
        The grid's nodes (MPa).
    pressures_mbar : array_like
        The pressures (mbar).
    probes : sequence of float
        Apertures (mm).
    curves_dir : path, optional
        Where to keep the curve files.
    name : str
        The space's name.

    Returns
    -------
    None
    """
    import tempfile
    from pathlib import Path

    from skinsuction.space import assemble_space, grid_points, point_id, row_id, write_curves

    from skinsuction.model import Skin

    spec = {"probes_mm": list(probes), "x1d": list(dermis_X1), "x1h": list(hypodermis_X1)}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(curves_dir) if curves_dir is not None else Path(tmp)
        rows = {}
        for params in grid_points(spec):
            skin = Skin.two_layer(params["x1d"], params["x1h"], bottom=params["bottom"])
            c = surrogate_curve(skin, params["probe_mm"], pressures_mbar=pressures_mbar)
            rows.setdefault(row_id(point_id(params)), []).append((c, params, {}))
        paths = [write_curves(points, folder / f"{row}.parquet", {"surrogate": True})
                 for row, points in rows.items()]
        assemble_space(paths, path, config={"spaces": {name: spec}, "surrogate": True},
                       name=name)
