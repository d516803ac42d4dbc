"""The forward model of the suction test (axisymmetric, two layers, finite strain)."""

from ._curve import Curve, ParameterError
from ._geometry import MeshSettings, edge_fan, suction_mesh
from ._material import SkinLayers, bulk_modulus, prestress, thickness_stretch
from ._simulate import BOTTOM_CONDITIONS, DEFAULT_PRESSURES_MBAR, SuctionTest, simulate

__all__ = [
    "BOTTOM_CONDITIONS",
    "Curve",
    "DEFAULT_PRESSURES_MBAR",
    "MeshSettings",
    "ParameterError",
    "SkinLayers",
    "SuctionTest",
    "bulk_modulus",
    "edge_fan",
    "prestress",
    "thickness_stretch",
    "simulate",
]
