"""Identification of the elastic properties of skin layers from suction tests.

Two-layer (dermis over hypodermis) axisymmetric FE model of the suction
(Cutometer) test, simulated spaces of apex-deflection curves on parameter grids,
and inverse identification against measured curves.

The public names are imported lazily, so ``import skinsuction`` is cheap and does
not need the FE stack until it is used:

>>> import skinsuction
>>> skinsuction.expand_axis({"start": 0, "stop": 100, "step": 2})[-1]
100.0

``skinsuction.simulate`` and ``skinsuction.Curve`` come from
:mod:`skinsuction.model`; ``read_space`` and ``SimulatedSpace`` from
:mod:`skinsuction.space`; the public names of :mod:`skinsuction.identify` and
:mod:`skinsuction.measured` (their ``__all__``) are available here as well.
"""

from importlib import import_module as _import_module
from importlib import metadata as _metadata

try:
    __version__ = _metadata.version("skinsuction")
except _metadata.PackageNotFoundError:  # run from a source tree
    __version__ = "0.1.0+src"

#: public name -> module that defines it
_EXPORTS = {
    # forward model
    "simulate": "skinsuction.model",
    "Curve": "skinsuction.model",
    # simulated space
    "SimulatedSpace": "skinsuction.space",
    "read_space": "skinsuction.space",
    "assemble_space": "skinsuction.space",
    "write_curve": "skinsuction.space",
    "read_curve": "skinsuction.space",
    "expand_axis": "skinsuction.space",
    "grid_points": "skinsuction.space",
    "point_id": "skinsuction.space",
    "parse_point_id": "skinsuction.space",
    "convergence_summary": "skinsuction.space",
    # provenance, progress of long runs
    "provenance": "skinsuction.provenance",
    "Progress": "skinsuction._progress",
    # figures
    "plot_fig3": "skinsuction.figures.fig3",
    # the classical optimisers the window focusing is compared with (once in identify)
    "BaselineResult": "skinsuction.evaluation",
    "least_squares_from_random_starts": "skinsuction.evaluation",
    "differential_evolution_fit": "skinsuction.evaluation",
}

__all__ = sorted(_EXPORTS) + ["__version__"]


#: modules whose ``__all__`` is part of the flat API too (looked up on first use)
_FLAT_MODULES = ("skinsuction.identify", "skinsuction.space", "skinsuction.measured")


def _find(name):
    for module in _FLAT_MODULES:
        if name.startswith("_"):
            break
        try:
            mod = _import_module(module)
        except ImportError:
            continue
        if name in getattr(mod, "__all__", ()):
            return module
    return None


def _submodule(name):
    """The subpackage or module ``skinsuction.<name>``, imported, or None."""
    import sys
    from importlib.util import find_spec

    full = f"{__name__}.{name}"
    if full in sys.modules:
        return sys.modules[full]
    return _import_module(full) if find_spec(full) is not None else None


def __getattr__(name):
    # `from skinsuction import model` asks for the attribute first: a subpackage must
    # not send it through the flat API's search, which imports skinsuction.identify and
    # SciPy's stats (0.3 s, every FE job paid it)
    sub = None if name.startswith("_") or name in _EXPORTS else _submodule(name)
    if sub is not None:
        return sub
    module = _EXPORTS.get(name) or _find(name)
    if module is None:
        raise AttributeError(f"module 'skinsuction' has no attribute {name!r}")
    if name == "provenance":
        value = _import_module(module)
    else:
        value = getattr(_import_module(module), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_EXPORTS))
