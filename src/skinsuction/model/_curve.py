"""The result of one forward simulation of the suction test."""

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class Curve:
    """Apex deflection M(p) of one suction test, as far as the solver got.

    Attributes
    ----------
    pressure_mbar : ndarray
        The requested suction pressures (mbar), ascending, starting at 0.
    deflection_mm : ndarray
        Apex deflection (mm, positive into the probe) at each requested pressure;
        NaN beyond ``last_converged_mbar``.
    converged : bool
        True if every requested pressure was reached.
    last_converged_mbar : float
        The highest pressure at which equilibrium was found.
    reason : str
        Empty if converged, otherwise why the solver stopped.
    newton_iterations : int
        Total Newton iterations, including those of cut-back increments.
    dofs : int
        Number of degrees of freedom of the mesh.
    seconds : float
        Wall time of the solve (mesh and assembly included).
    info : dict
        Settings that produced the curve (mesh, material, boundary), for provenance.
    """

    pressure_mbar: np.ndarray
    deflection_mm: np.ndarray
    converged: bool
    last_converged_mbar: float
    reason: str = ""
    newton_iterations: int = 0
    dofs: int = 0
    seconds: float = 0.0
    info: dict = field(default_factory=dict)

    def to_frame(self):
        """The curve as a DataFrame with columns ``pressure_mbar, deflection_mm``."""
        import pandas as pd

        return pd.DataFrame(
            {"pressure_mbar": self.pressure_mbar, "deflection_mm": self.deflection_mm}
        )


class ParameterError(ValueError):
    """The model refuses its parameters or mesh settings (before any solve).

    A failed solve is a :class:`Curve` with ``converged=False``; refused
    parameters are a user's error, raised so that a workflow job fails loudly.
    """
