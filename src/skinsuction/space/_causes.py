"""The registry of causes: physical hypotheses that extend the neo-Hookean model.

A cause adds one parameter to the two-layer neo-Hookean model (X1d, X1h): a
keyword of :func:`skinsuction.model.simulate` whose ``neutral`` value gives the
baseline model back.  The registry is read from the configuration
(``diagnosis.causes``), so a new cause is a configuration entry plus, if the
model lacks it, a model option; nothing in the diagnosis is specific to one
cause.

The extended simulated spaces are stored as *rays* (see :mod:`._rays`): the
scaling law ``M(s X1d, s X1h, s X2d, s X2h, s p) = M(X1d, X1h, X2d, X2h, p)``
makes every dimensionless parameter (a ratio of moduli, a thickness, a stretch)
a coordinate of the ray, while X1d only rescales the pressure.  A cause whose
parameter is a modulus (``modulus: true``, e.g. X2d) therefore has the ray
coordinate ``value / X1d``; any other parameter is its own coordinate.

Examples
--------
>>> reg = default_registry()
>>> sorted(reg)
['dermis_thickness', 'hypodermis_thickness', 'pre_tension', 'strain_stiffening']
>>> c = reg["strain_stiffening"]
>>> c.symbol, c.unit, c.value(coordinate=2.0, dermis_X1=0.05)
('X2d', 'MPa', 0.1)
>>> c.coordinate(value=0.1, dermis_X1=0.05)
2.0
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np

from ._storage import AXIS_PATHS

__all__ = ["Cause", "NONE", "BASELINE", "registry_from_config", "default_registry",
           "DEFAULT_CAUSES"]

#: Axis transforms of a cause coordinate c: (c -> u, u -> c).
SCALES = {
    "linear": (lambda c: c, lambda u: u),
    "log": (np.log10, lambda u: 10.0 ** u),
    "log1p": (lambda c: np.log10(1.0 + c), lambda u: 10.0 ** u - 1.0),
}

#: Model keywords that are layer thicknesses (mm): causes that a measured
#: thickness (file header, study column, option) takes out of the diagnosis.
GEOMETRY_KEYWORDS = ("t_d", "t_h")

#: The parameter paths of the skin (:class:`skinsuction.model.Skin`) that a
#: cause's keyword frees: the one place the two-layer keywords meet the skin.
KEYWORD_PATHS = {
    **{key: (AXIS_PATHS[key],) for key in ("x2d", "x2h", "t_d", "t_h")},
    "prestretch": ("dermis.prestretch", "hypodermis.prestretch"),
}

#: Name of the verdict "the neo-Hookean model explains the data".
NONE = "none"
#: Name of the baseline model (and of its ray space).
BASELINE = "neo_hookean"


@dataclass(frozen=True)
class Cause:
    """One candidate cause of misfit: a physical hypothesis with one extra parameter.

    Attributes
    ----------
    name : str
        Registry key, e.g. ``"strain_stiffening"``.
    keyword : str
        Keyword of the two-layer grid point that sets the parameter (``x2d``,
        ``t_d``, ``prestretch``, ...); :attr:`paths` names the skin parameters it
        frees (:data:`KEYWORD_PATHS`), :meth:`apply` sets them on a skin.
    symbol : str
        Name of the parameter in reports (``X2d``, ``t_d``, ``lambda0``).
    unit : str
        Unit of the parameter (``MPa``, ``mm``, ``1``).
    modulus : bool
        True if the parameter is a modulus: it scales with X1d and the ray
        coordinate is ``value / X1d``; otherwise the coordinate is the value.
    neutral : float
        Coordinate of the baseline model (0 for X2d, 1 mm for t_d, 1 for lambda0);
        must be one of ``nodes``.
    nodes : tuple of float
        Ray coordinates simulated (ascending); the space spans ``nodes[0]..nodes[-1]``.
    hypothesis : str
        The physical hypothesis, one sentence.
    description : str
        What the parameter is, for reports.
    scale : {"linear", "log", "log1p"}
        Axis on which the nodes are interpolated and the fit searches:
        ``u = c``, ``u = log10 c`` or ``u = log10(1 + c)`` (a log-like axis that
        keeps 0: X2d/X1d from 0 to 1000 on nearly even steps).
    """

    name: str
    keyword: str
    symbol: str
    unit: str
    modulus: bool
    neutral: float
    nodes: tuple
    hypothesis: str = ""
    description: str = ""
    coordinate_name: str = field(default="")
    scale: str = "linear"

    def __post_init__(self):
        nodes = tuple(float(v) for v in self.nodes)
        object.__setattr__(self, "nodes", nodes)
        object.__setattr__(self, "neutral", float(self.neutral))
        if len(nodes) < 2 or not np.all(np.diff(nodes) > 0):
            raise ValueError(f"cause {self.name!r}: nodes must be >= 2 ascending values, "
                             f"got {list(nodes)}")
        if not any(np.isclose(self.neutral, v, rtol=0, atol=1e-12) for v in nodes):
            raise ValueError(f"cause {self.name!r}: the neutral value {self.neutral:g} (baseline "
                             f"model) must be one of the nodes {list(nodes)}")
        if self.scale not in SCALES:
            raise ValueError(f"cause {self.name!r}: scale must be one of {sorted(SCALES)}, "
                             f"got {self.scale!r}")
        if self.scale == "log" and nodes[0] <= 0:
            raise ValueError(f"cause {self.name!r}: a log scale needs positive nodes")
        if self.scale == "log1p" and nodes[0] <= -1:
            raise ValueError(f"cause {self.name!r}: a log1p scale needs nodes above -1")
        if self.name in (NONE, BASELINE):
            raise ValueError(f"{self.name!r} is reserved and cannot name a cause")
        if not self.coordinate_name:
            object.__setattr__(self, "coordinate_name",
                               f"{self.symbol}/X1d" if self.modulus else self.symbol)

    @property
    def geometric(self) -> bool:
        """True for a layer thickness: not a free cause where the thickness is given."""
        return self.keyword in GEOMETRY_KEYWORDS

    @property
    def lower(self) -> float:
        """The lowest coordinate simulated (``nodes[0]``)."""
        return self.nodes[0]

    @property
    def upper(self) -> float:
        """The highest coordinate simulated (``nodes[-1]``)."""
        return self.nodes[-1]

    def to_axis(self, coordinate):
        """Interpolation/search axis ``u`` of a ray coordinate (see ``scale``).

        Parameters
        ----------
        coordinate : float or array_like
            Ray coordinates.

        Returns
        -------
        float or ndarray
            ``u``, of the same shape.
        """
        c = np.asarray(coordinate, dtype=float)
        u = SCALES[self.scale][0](c)
        return float(u) if np.ndim(u) == 0 else u

    def from_axis(self, u):
        """Ray coordinate of an axis value (inverse of :meth:`to_axis`).

        Parameters
        ----------
        u : float or array_like
            Axis values.

        Returns
        -------
        float or ndarray
            Ray coordinates, of the same shape.
        """
        c = SCALES[self.scale][1](np.asarray(u, dtype=float))
        return float(c) if np.ndim(c) == 0 else c

    @property
    def axis_nodes(self) -> np.ndarray:
        """The nodes on the interpolation axis ``u`` (:meth:`to_axis`)."""
        return np.asarray(self.to_axis(np.asarray(self.nodes)), dtype=float)

    def value(self, coordinate, dermis_X1):
        """Parameter value (in ``unit``) of a ray coordinate.

        Parameters
        ----------
        coordinate : float or array_like
            Ray coordinates (``value / X1d`` for a modulus, else the value).
        dermis_X1 : float or array_like
            The skin's ``dermis.X1`` (MPa), which scales a modulus; broadcast
            with ``coordinate``.

        Returns
        -------
        float or ndarray
        """
        c = np.asarray(coordinate, dtype=float)
        out = c * np.asarray(dermis_X1, dtype=float) if self.modulus else c
        return float(out) if np.ndim(out) == 0 else out

    def coordinate(self, value, dermis_X1):
        """Ray coordinate of a parameter value (inverse of :meth:`value`).

        Parameters
        ----------
        value : float or array_like
            Parameter values (in ``unit``).
        dermis_X1 : float or array_like
            The skin's ``dermis.X1`` (MPa).

        Returns
        -------
        float or ndarray
        """
        v = np.asarray(value, dtype=float)
        out = v / np.asarray(dermis_X1, dtype=float) if self.modulus else v
        return float(out) if np.ndim(out) == 0 else out

    def simulate_keywords(self, coordinate, dermis_X1) -> dict:
        """The two-layer grid point's keyword for this coordinate, as a ray id spells it.

        Parameters
        ----------
        coordinate : float
            The ray coordinate.
        dermis_X1 : float
            The skin's ``dermis.X1`` (MPa) the ray is run at.

        Returns
        -------
        dict
            ``{keyword: value}``, e.g. ``{"x2d": 0.02}``; :meth:`apply` sets the
            same value on a skin by its :attr:`paths`.
        """
        return {self.keyword: float(self.value(coordinate, dermis_X1))}

    @property
    def paths(self) -> tuple:
        """The parameter paths of the skin this cause frees (e.g. ``("dermis.X2",)``;
        pre-tension frees the pre-stretch of every layer)."""
        try:
            return KEYWORD_PATHS[self.keyword]
        except KeyError:
            raise ValueError(f"cause {self.name!r}: keyword {self.keyword!r} names no skin "
                             f"parameter; known: {sorted(KEYWORD_PATHS)}") from None

    def apply(self, skin, coordinate):
        """The skin with this cause's parameter at a ray coordinate.

        Parameters
        ----------
        skin : Skin
            The neo-Hookean skin (its dermis X1 scales a modulus cause).
        coordinate : float
            The ray coordinate (``value / X1d`` for a modulus, else the value).

        Returns
        -------
        Skin

        Examples
        --------
        >>> from skinsuction.model import Skin
        >>> stiff = default_registry()["strain_stiffening"].apply(Skin.two_layer(0.05, 5e-4), 2.0)
        >>> stiff.get("dermis.X2")
        0.1
        """
        value = float(self.value(coordinate, skin.get("dermis.X1")))
        return skin.replace({path: value for path in self.paths})

    def to_dict(self) -> dict:
        """The cause as plain JSON-able values (:meth:`from_dict` reads it back).

        Returns
        -------
        dict
        """
        d = asdict(self)
        d["nodes"] = list(self.nodes)
        return d

    @classmethod
    def from_dict(cls, d: dict) -> "Cause":
        """A cause of :meth:`to_dict`'s form (unknown keys are ignored).

        Parameters
        ----------
        d : dict

        Returns
        -------
        Cause
        """
        return cls(**{k: v for k, v in d.items() if k in cls.__dataclass_fields__})


#: Built-in registry, the same as ``diagnosis.causes`` of config/config.yaml.
DEFAULT_CAUSES = {
    "strain_stiffening": dict(
        keyword="x2d", symbol="X2d", unit="MPa", modulus=True, neutral=0.0, scale="log1p",
        nodes=[0.0, 1.0, 3.0, 10.0, 30.0, 100.0, 300.0, 1000.0],
        hypothesis="the dermis stiffens faster with strain than neo-Hookean (collagen "
                   "recruitment): W = X1 (I1 - 3) + X2 (I1 - 3)^2 (paper eq. 9)",
        description="second-order modulus X2 of the dermis (MPa)",
    ),
    "dermis_thickness": dict(
        keyword="t_d", symbol="t_d", unit="mm", modulus=False, neutral=1.0, scale="log",
        nodes=[0.4, 0.5, 0.6, 0.75, 1.0, 1.2, 1.5, 1.8, 2.2, 2.6, 3.0],
        hypothesis="the dermis is not 1 mm thick (in vivo about 0.5-2.5 mm with site "
                   "and age)",
        description="thickness of the dermis with the epidermis (mm)",
    ),
    "hypodermis_thickness": dict(
        keyword="t_h", symbol="t_h", unit="mm", modulus=False, neutral=1.0, scale="log",
        nodes=[0.5, 0.65, 0.85, 1.0, 1.3, 1.7, 2.2, 3.0, 4.5, 7.0, 10.0],
        hypothesis="the hypodermis is not 1 mm thick (on the forearm often several mm): "
                   "the probe feels the bone less, or more, than the model assumes",
        description="thickness of the hypodermis over a fixed bottom (mm)",
    ),
    "pre_tension": dict(
        keyword="prestretch", symbol="lambda0", unit="1", modulus=False, neutral=1.0,
        nodes=[1.0, 1.05, 1.1, 1.15, 1.2, 1.25],
        hypothesis="the skin is under natural in-plane tension before the probe is "
                   "glued (reported initial stresses around 10 kPa)",
        description="equibiaxial in-plane pre-stretch lambda0 of both layers",
    ),
}


def registry_from_config(causes: dict) -> dict:
    """``{name: Cause}`` from the ``diagnosis.causes`` mapping of the configuration.

    Every entry needs ``keyword``, ``symbol``, ``unit``, ``neutral`` and ``nodes``
    (``modulus`` defaults to False).  Node lists may use the axis forms of the
    configuration (see :func:`skinsuction.space.expand_axis`).

    Parameters
    ----------
    causes : dict
        ``{name: {keyword, symbol, unit, neutral, nodes, ...}}``.

    Returns
    -------
    dict
        ``{name: Cause}``.

    Raises
    ------
    ValueError
        Naming the entry (``diagnosis.causes.<name>``) and what is wrong with it.
    """
    from ._grid import expand_axis

    out = {}
    for name, spec in (causes or {}).items():
        spec = {"modulus": False, **dict(spec)}
        try:
            spec["nodes"] = sorted(expand_axis(spec["nodes"]))
            out[name] = Cause(name=name, **{k: v for k, v in spec.items()
                                            if k in Cause.__dataclass_fields__})
        except (KeyError, TypeError, ValueError) as err:
            raise ValueError(f"diagnosis.causes.{name}: {err}") from None
    return out


def default_registry() -> dict:
    """The built-in registry (:data:`DEFAULT_CAUSES`).

    Returns
    -------
    dict
        ``{name: Cause}``.
    """
    return registry_from_config(DEFAULT_CAUSES)
