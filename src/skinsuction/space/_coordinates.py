"""The coordinates of the simulated space, derived from a skin in one place.

The scale-free space stores a dermis over a hypodermis under a probe of radius
``a`` by quantities in which the deflection is a function of fewer variables
(the neo-Hookean stack is homogeneous of degree one in its moduli, and
geometrically similar in its lengths):

* the scale ``X1d`` (``dermis.X1``): every modulus is divided by it, the
  suction too, so a curve is read at the *load* ``q = p / X1d`` (mbar/MPa,
  :func:`load`), or on a ray run at ``x1d_ref`` at the suction of the same load
  (:func:`reference_pressure`);
* the *ratio* ``r = X1h / X1d``;
* the *geometry*: each layer's ``t / a``; rays on demand are solved at
  ``a = 1 mm`` and their deflections multiplied by ``a`` (:func:`similar_length`);
* the *cause coordinate* ``c``: a modulus over ``X1d`` (``X2d / X1d``), else
  the value itself (``lambda0``, a thickness in mm)
  (:meth:`skinsuction.space.Cause.coordinate`).

:class:`SpaceCoordinates` holds them for one skin (:meth:`SpaceCoordinates.of`)
and gives the skin back (:meth:`SpaceCoordinates.skin`): the round trip is exact
for every skin the space can hold.

Examples
--------
A stiffening skin on measured layers, and back:

>>> from skinsuction.model import Skin
>>> from skinsuction.space import default_registry
>>> stiff = default_registry()["strain_stiffening"]
>>> skin = Skin.two_layer(0.05, 5e-4, x2d=0.1, t_d=1.3, t_h=2.7)
>>> c = SpaceCoordinates.of(skin, stiff)
>>> c.ratio, c.coordinate, round(c.similar_layers(6.0)["dermis.thickness"], 4)
(0.01, 2.0, 0.4333)
>>> c.skin() == skin
True
>>> float(load(100.0, c.dermis_X1))  # mbar/MPa
2000.0
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from skinsuction.model import Skin

from ._causes import Cause
from ._storage import AXIS_PATHS

__all__ = ["SpaceCoordinates", "load", "reference_pressure", "similar_length",
           "LAYER_PATHS"]

#: The layers of the space: a dermis over a hypodermis, by thickness path.
LAYER_PATHS = (AXIS_PATHS["t_d"], AXIS_PATHS["t_h"])


def load(pressure_mbar, dermis_X1):
    """The load ``q = p / X1d`` (mbar/MPa) at which a skin's curve is read.

    Parameters
    ----------
    pressure_mbar : float or array_like
        The suction (mbar).
    dermis_X1 : float or array_like
        ``dermis.X1`` (MPa); broadcast with the suction.

    Returns
    -------
    float or ndarray
    """
    return np.asarray(pressure_mbar, dtype=float) / np.asarray(dermis_X1, dtype=float)


def reference_pressure(pressure_mbar, dermis_X1, x1d_ref):
    """The suction on a ray run at ``x1d_ref`` that puts the same load on it.

    ``p x1d_ref / X1d``: a ray at ``x1d_ref`` read there gives the curve of the
    skin at ``X1d`` (same ratio, layers and cause coordinate).

    Parameters
    ----------
    pressure_mbar : float or array_like
        The skin's suction (mbar).
    dermis_X1 : float or array_like
        Its ``dermis.X1`` (MPa); broadcast with the suction.
    x1d_ref : float
        The rays' ``dermis.X1`` (MPa).

    Returns
    -------
    float or ndarray
        The ray's suction (mbar).
    """
    return np.asarray(pressure_mbar, dtype=float) * (x1d_ref / np.asarray(dermis_X1,
                                                                          dtype=float))


def similar_length(length_mm, probe_mm):
    """A length over the aperture radius ``a = probe_mm / 2`` (geometric similarity).

    Parameters
    ----------
    length_mm : float
        A layer thickness or a thickness cause's coordinate (mm).
    probe_mm : float
        The aperture diameter (mm).

    Returns
    -------
    float
        ``length / a``: the length at a 2 mm aperture with the same curve over ``a``.
    """
    return float(length_mm) / (float(probe_mm) / 2)


@dataclass(frozen=True)
class SpaceCoordinates:
    """Where a skin sits in the simulated space (see the module docstring).

    Attributes
    ----------
    dermis_X1 : float
        The scale (MPa).
    ratio : float
        ``hypodermis.X1 / dermis.X1``.
    layers : dict
        ``{"dermis.thickness": mm, "hypodermis.thickness": mm}`` without a
        thickness cause's (its coordinate holds it).
    bottom : str
        The bottom condition (one space per bottom).
    cause : Cause or None
        The cause whose coordinate is held (None: the neo-Hookean skin).
    coordinate : float
        The cause coordinate (NaN without a cause).
    """

    dermis_X1: float
    ratio: float
    layers: dict
    bottom: str = "fixed"
    cause: Cause | None = None
    coordinate: float = math.nan

    @classmethod
    def of(cls, skin: Skin, cause: Cause | None = None) -> "SpaceCoordinates":
        """The coordinates of a dermis over a hypodermis.

        Parameters
        ----------
        skin : Skin
            Two layers named ``dermis`` and ``hypodermis``.
        cause : Cause, optional
            The cause whose parameter the skin carries; every other parameter
            must be neo-Hookean (X2 = 0, no pre-stretch).

        Returns
        -------
        SpaceCoordinates

        Raises
        ------
        ValueError
            Another stack, or a parameter the space (with that cause) does not hold.
        """
        if skin.names != ("dermis", "hypodermis"):
            raise ValueError(f"the simulated space holds a dermis over a hypodermis, not the "
                             f"layers {list(skin.names)}")
        freed = set(cause.paths) if cause is not None else set()
        neutral = {"dermis.X2": 0.0, "hypodermis.X2": 0.0, "dermis.prestretch": 1.0,
                   "hypodermis.prestretch": 1.0}
        extra = [f"{p} = {skin.get(p):g}" for p, v in neutral.items()
                 if p not in freed and skin.get(p) != v]
        if any(layer.spectrum.terms for layer in skin.layers):
            extra.append("a relaxation spectrum")
        if extra:
            raise ValueError(f"the simulated space {'of ' + cause.name if cause else ''} "
                             f"does not hold {', '.join(extra)}".replace("  ", " "))
        x1d = skin.get("dermis.X1")
        layers = {p: skin.get(p) for p in LAYER_PATHS if p not in freed}
        coordinate = math.nan
        if cause is not None:
            coordinate = float(cause.coordinate(skin.get(cause.paths[0]), x1d))
        return cls(x1d, skin.get("hypodermis.X1") / x1d, layers, skin.bottom, cause,
                   coordinate)

    def skin(self, layers: dict | None = None) -> Skin:
        """The skin at these coordinates.

        Parameters
        ----------
        layers : dict, optional
            Thicknesses by path (mm) for the layers the coordinates leave out
            (default the paper's 1 mm); a thickness cause's comes from its coordinate.

        Returns
        -------
        Skin
        """
        t = {p: 1.0 for p in LAYER_PATHS}
        t.update(layers or {})
        t.update(self.layers)
        skin = Skin.two_layer(self.dermis_X1, self.ratio * self.dermis_X1,
                              t_d=t["dermis.thickness"], t_h=t["hypodermis.thickness"],
                              bottom=self.bottom)
        if self.cause is not None:
            skin = self.cause.apply(skin, self.coordinate)
        return skin

    def similar_layers(self, probe_mm: float) -> dict:
        """The layers' ``t / a`` under a probe (:func:`similar_length`), by path."""
        return {p: similar_length(t, probe_mm) for p, t in self.layers.items()}
