"""Spectra per layer for the two-layer viscoelastic model (the spectrum itself,
:class:`skinsuction.model.Prony`, is part of the skin's description)."""

from __future__ import annotations

from ..model import ParameterError, Prony

__all__ = ["Prony", "layer_spectra"]

def layer_spectra(prony):
    """``(dermis, hypodermis)`` spectra from one shared :class:`Prony`, a pair, or
    a mapping with keys ``"dermis"`` and ``"hypodermis"``.

    Examples
    --------
    >>> d, h = layer_spectra({"dermis": Prony([0.5], [0.1]), "hypodermis": Prony.elastic()})
    >>> d.terms, h.terms
    (1, 0)
    """
    if prony is None:
        return Prony.elastic(), Prony.elastic()
    if isinstance(prony, Prony):
        return prony, prony
    if isinstance(prony, dict):
        unknown = set(prony) - {"dermis", "hypodermis"}
        if unknown:
            raise ParameterError(f"prony: unknown layers {sorted(unknown)}")
        return (prony.get("dermis", Prony.elastic()), prony.get("hypodermis", Prony.elastic()))
    dermis, hypodermis = prony
    return dermis, hypodermis
