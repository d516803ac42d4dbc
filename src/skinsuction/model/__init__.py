"""The forward model of the suction test (axisymmetric, a stack of layers, finite strain).

A skin is described once (:class:`Skin`: its layers, top first, and the bottom
condition); :class:`Probe` and :class:`Ramp` stand beside it. :func:`simulate`
solves a skin under a probe for M(p).
"""

from ._curve import Curve, ParameterError
from ._fast import SWAP, FastAssembly, material_response
from ._geometry import MeshSettings, edge_fan, layer_breaks, suction_mesh
from ._inp import CalculixError, inp_deck, read_dat, run_calculix, write_inp
from ._material import SkinLayers, bulk_modulus, prestress, thickness_stretch
from ._prony import Prony
from ._simulate import (
    DEFAULT_PRESSURES_MBAR, MBAR_TO_MPA, NoEquilibrium, SuctionTest, layer_prestretch, simulate,
)
from ._skin import BOTTOM_CONDITIONS, MAX_LAYERS, Layer, Probe, Ramp, Skin

__all__ = [
    "BOTTOM_CONDITIONS",
    "CalculixError",
    "Curve",
    "DEFAULT_PRESSURES_MBAR",
    "FastAssembly",
    "MBAR_TO_MPA",
    "NoEquilibrium",
    "SWAP",
    "Layer",
    "MAX_LAYERS",
    "MeshSettings",
    "ParameterError",
    "Probe",
    "Prony",
    "Ramp",
    "Skin",
    "SkinLayers",
    "SuctionTest",
    "bulk_modulus",
    "edge_fan",
    "inp_deck",
    "layer_breaks",
    "layer_prestretch",
    "material_response",
    "prestress",
    "read_dat",
    "run_calculix",
    "thickness_stretch",
    "simulate",
    "suction_mesh",
    "write_inp",
]
