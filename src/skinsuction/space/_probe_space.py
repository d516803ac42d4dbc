"""What identify and diagnose ask of the simulated space of one probe, in either layout."""

from __future__ import annotations

from typing import Protocol

import numpy as np

__all__ = ["ProbeSpace"]


class ProbeSpace(Protocol):
    """What identify and diagnose ask of the simulated space of one probe.

    Attributes
    ----------
    layout : {"grid", "scale_free"}
        Which layout (for messages that name configuration keys).
    probe_mm : float
        Aperture diameter.
    coordinates : tuple of str
        Names of the candidates' coordinates (moduli on a grid, logs on rays).
    pressure_range : (float, float)
        Pressures (mbar) a measured curve may span.
    """

    layout: str
    probe_mm: float
    coordinates: tuple
    pressure_range: tuple

    def interpolant_at(self, pressure_mbar, nan_policy: str = "shift"):
        """The space at fixed pressures.

        Parameters
        ----------
        pressure_mbar : array_like, shape (u,)
            The measured pressures (mbar).
        nan_policy : str
            How non-converged nodes are handled (``"shift"``; a grid also has
            ``"strict"``).

        Returns
        -------
        callable
            ``(N, d) candidates -> (N, u)`` deflections (mm), with ``lower`` and
            ``upper`` bounds of the candidates.
        """

    def to_moduli(self, candidates) -> np.ndarray:
        """X1d, X1h of candidates.

        Parameters
        ----------
        candidates : array_like, shape (N, d)

        Returns
        -------
        ndarray, shape (N, 2)
            X1d, X1h in MPa.
        """

    def from_moduli(self, moduli) -> np.ndarray:
        """Candidates of moduli (inverse of :meth:`to_moduli`).

        Parameters
        ----------
        moduli : array_like, shape (N, 2)
            X1d, X1h in MPa.

        Returns
        -------
        ndarray, shape (N, d)
        """

    def range_note(self) -> str:
        """What sets ``pressure_range``, for error messages.

        Returns
        -------
        str
        """
