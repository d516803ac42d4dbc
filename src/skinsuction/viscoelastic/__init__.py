"""Viscoelastic skin layers: relaxation spectra over the long-time hyperelastic model.

* :class:`Prony`: fractions ``g_i`` of the long-time moduli and times ``tau_i``
  (instantaneous moduli ``X1 (1 + sum g_i)``), one per layer or shared;
* :func:`simulate_history`: the two-layer FE model under a suction history p(t),
  implicit time steps over internal variables (second order in the step);
* :func:`fast_history`: the elastic equilibrium curve under the effective load
  ``p_eff = int psi(t - s) dp(s)`` (the creep function of the spectrum);
* :func:`mode1_history`, :func:`mode2_history`: Cutometer histories with graded steps.

See ``docs/viscoelasticity.md``.
"""

from ._fast_path import effective_pressure, fast_history
from ._fe import BRANCHES, History, ViscoelasticSuctionTest, ViscousAssembly, simulate_history
from ._histories import PressureHistory, graded_steps, mode1_history, mode2_history
from ._prony import Prony, layer_spectra

__all__ = [
    "BRANCHES",
    "History",
    "PressureHistory",
    "Prony",
    "ViscoelasticSuctionTest",
    "ViscousAssembly",
    "effective_pressure",
    "fast_history",
    "graded_steps",
    "layer_spectra",
    "mode1_history",
    "mode2_history",
    "simulate_history",
]
