"""One description of a skin: an ordered stack of layers on a bottom condition,
the probe that measures it and the suction ramp it applies.

Every layer carries its own thickness, hyperelastic law ``W = X1 (I1bar - 3) +
X2 (I1bar - 3)^2`` (MPa), relaxation spectrum (:class:`Prony`, long-time moduli)
and in-plane pre-stretch. A fitted parameter is a *path* into the skin:
``"dermis.X1"``, ``"hypodermis.thickness"``, ``"dermis.spectrum.g[0]"``.

Units: thicknesses and apertures in mm, moduli in MPa, times in s, pressures in
mbar. A skin round-trips through JSON and YAML (:meth:`Skin.to_dict`,
:meth:`Skin.from_dict`, :meth:`Skin.read`, :meth:`Skin.write`).
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from ._curve import ParameterError
from ._prony import Prony

__all__ = ["BOTTOM_CONDITIONS", "Layer", "Probe", "Ramp", "Skin", "MAX_LAYERS"]

BOTTOM_CONDITIONS = ("fixed", "axial", "free")
#: the forward model's stack: one to four layers
MAX_LAYERS = 4
#: the numeric fields of a layer a path may name (spectrum terms aside)
LAYER_FIELDS = ("thickness", "X1", "X2", "prestretch")
_NAME = re.compile(r"^[a-z][a-z0-9_]*$")
_PATH = re.compile(r"^([a-z][a-z0-9_]*)\.(thickness|X1|X2|prestretch|spectrum\.(g|tau_s)\[(\d+)\])$")
# plausibility bounds: a value outside is a unit error (e.g. kPa or m), not a skin
_RANGES = {"thickness": (0.0, 100.0, "mm"), "X1": (0.0, 1e4, "MPa"),
           "X2": (0.0, 1e5, "MPa"), "prestretch": (0.5, 2.0, "")}


def _number(value, where):
    try:
        out = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{where} must be a number, not {value!r}") from None
    if not np.isfinite(out):
        raise ParameterError(f"{where} must be finite, not {value!r}")
    return out


@dataclass(frozen=True)
class Layer:
    """One skin layer.

    Parameters
    ----------
    name : str
        Lower-case identifier, e.g. ``"superficial"``, ``"dermis"``, ``"hypodermis"``.
    thickness : float
        Thickness in mm (of the skin as it lies, pre-stretched).
    X1, X2 : float
        Long-time moduli of ``W = X1 (I1bar - 3) + X2 (I1bar - 3)^2`` in MPa
        (X1 > 0; X2 >= 0, 0 is neo-Hookean).
    spectrum : Prony, optional
        Relaxation spectrum over the long-time moduli (default: elastic).
    prestretch : float, optional
        Equibiaxial in-plane pre-stretch lambda0 of the layer (1: none).

    Examples
    --------
    >>> Layer("dermis", 1.0, 0.08).X2
    0.0
    """

    name: str
    thickness: float
    X1: float
    X2: float = 0.0
    spectrum: Prony = field(default_factory=Prony)
    prestretch: float = 1.0

    def __post_init__(self):
        if not isinstance(self.name, str) or not _NAME.match(self.name):
            raise ParameterError(
                f"layer name {self.name!r} must be a lower-case identifier (e.g. 'dermis')")
        for key in LAYER_FIELDS:
            where = f"{self.name}.{key}"
            value = _number(getattr(self, key), where)
            low, high, unit = _RANGES[key]
            open_low = key in ("thickness", "X1")
            if (value <= low if open_low else value < low) or value > high:
                bound = f"({low:g}, {high:g}]" if open_low else f"[{low:g}, {high:g}]"
                raise ParameterError(
                    f"{where} = {value:g} lies outside {bound} {unit}".rstrip()
                    + (" (units: mm and MPa)" if unit else ""))
            object.__setattr__(self, key, value)
        spectrum = self.spectrum
        if isinstance(spectrum, dict):
            spectrum = Prony(**spectrum)
        elif spectrum is None:
            spectrum = Prony()
        if not isinstance(spectrum, Prony):
            raise ParameterError(f"layer {self.name!r}: spectrum must be a Prony or "
                                 f"{{g: [...], tau_s: [...]}}, not {spectrum!r}")
        object.__setattr__(self, "spectrum", spectrum)

    def to_dict(self) -> dict:
        """The layer as plain JSON-able values (the spectrum only if it has terms)."""
        out = {"name": self.name, "thickness": self.thickness, "X1": self.X1, "X2": self.X2,
               "prestretch": self.prestretch}
        if self.spectrum.terms:
            out["spectrum"] = {"g": list(self.spectrum.g), "tau_s": list(self.spectrum.tau_s)}
        return out


@dataclass(frozen=True)
class Skin:
    """An ordered stack of layers, top (the surface under the probe) first, on a
    bottom condition.

    Parameters
    ----------
    layers : sequence of Layer or dict
        One to four layers, top first, with distinct names.
    bottom : {"fixed", "axial", "free"}
        The bottom of the stack: both directions restrained, axial only, or none.

    Examples
    --------
    The paper's skin, and the same with a soft superficial layer on top:

    >>> skin = Skin.two_layer(0.08, 4.1e-4)
    >>> skin.names, skin.get("hypodermis.X1")
    (('dermis', 'hypodermis'), 0.00041)
    >>> three = skin.with_layer_on_top("superficial", 0.1, 0.02)
    >>> three.names, three.thicknesses
    (('superficial', 'dermis', 'hypodermis'), (0.1, 1.0, 1.0))
    >>> three.replace({"dermis.X1": 0.05}).get("dermis.X1")
    0.05
    >>> Skin.from_dict(three.to_dict()) == three
    True
    """

    layers: tuple
    bottom: str = "fixed"

    def __post_init__(self):
        layers = tuple(Layer(**dict(v)) if isinstance(v, dict) else v for v in self.layers)
        if not 1 <= len(layers) <= MAX_LAYERS:
            raise ParameterError(
                f"a skin has 1 to {MAX_LAYERS} layers, not {len(layers)}")
        for k, layer in enumerate(layers):
            if not isinstance(layer, Layer):
                raise ParameterError(f"layers[{k}] must be a Layer or a mapping, not {layer!r}")
        names = [layer.name for layer in layers]
        if len(set(names)) != len(names):
            raise ParameterError(f"layer names must be distinct, not {names}")
        if self.bottom not in BOTTOM_CONDITIONS:
            raise ParameterError(
                f"bottom must be one of {BOTTOM_CONDITIONS}, not {self.bottom!r}")
        object.__setattr__(self, "layers", layers)

    # ------------------------------------------------------------ construction
    @classmethod
    def two_layer(cls, x1d, x1h, x2d=0.0, x2h=0.0, t_d=1.0, t_h=1.0, bottom="fixed",
                  prestretch=1.0, spectrum=None):
        """The paper's skin: a dermis over a hypodermis.

        Parameters
        ----------
        x1d, x1h, x2d, x2h : float
            Moduli of the dermis (d) and the hypodermis (h), MPa.
        t_d, t_h : float
            Thicknesses in mm (the paper's: 1 mm each).
        bottom : {"fixed", "axial", "free"}
            The bottom condition.
        prestretch : float
            In-plane pre-stretch of both layers (1: none).
        spectrum : Prony or dict, optional
            One spectrum shared by both layers, or ``{"dermis": ..., "hypodermis":
            ...}`` (a missing layer is elastic).

        Returns
        -------
        Skin
        """
        if isinstance(spectrum, dict):
            unknown = set(spectrum) - {"dermis", "hypodermis"}
            if unknown:
                raise ParameterError(f"spectrum: unknown layers {sorted(unknown)}")
            spectra = (spectrum.get("dermis"), spectrum.get("hypodermis"))
        else:
            spectra = (spectrum, spectrum)
        return cls((Layer("dermis", t_d, x1d, x2d, spectra[0], prestretch),
                    Layer("hypodermis", t_h, x1h, x2h, spectra[1], prestretch)), bottom)

    def with_layer_on_top(self, name, thickness, X1, X2=0.0, spectrum=None, prestretch=None):
        """This skin under a new top layer (e.g. epidermis with papillary dermis).

        Parameters
        ----------
        name : str
            The new layer's name.
        thickness, X1, X2 : float
            Its thickness (mm) and moduli (MPa).
        spectrum : Prony, optional
            Its spectrum (default: elastic).
        prestretch : float, optional
            Its pre-stretch (default: that of the layer below it).

        Returns
        -------
        Skin
        """
        lam = self.layers[0].prestretch if prestretch is None else prestretch
        return Skin((Layer(name, thickness, X1, X2, spectrum, lam),) + self.layers, self.bottom)

    # ---------------------------------------------------------------- queries
    @property
    def names(self) -> tuple:
        """Layer names, top first."""
        return tuple(layer.name for layer in self.layers)

    @property
    def thicknesses(self) -> tuple:
        """Layer thicknesses (mm), top first."""
        return tuple(layer.thickness for layer in self.layers)

    @property
    def depth(self) -> float:
        """Total thickness of the stack (mm)."""
        return float(sum(self.thicknesses))

    @property
    def has_prestretch(self) -> bool:
        """True if any layer is pre-stretched."""
        return any(layer.prestretch != 1.0 for layer in self.layers)

    def __getitem__(self, name) -> Layer:
        return self.layers[self.index(name)]

    def index(self, name) -> int:
        """Position of the layer ``name`` in the stack (0: top)."""
        try:
            return self.names.index(name)
        except ValueError:
            raise ParameterError(
                f"the skin has no layer {name!r}; its layers: {list(self.names)}") from None

    # ----------------------------------------------------------------- paths
    def _parse(self, path):
        m = _PATH.match(str(path))
        if not m:
            raise ParameterError(
                f"{path!r} is not a parameter path; paths are '<layer>.<field>' with "
                f"field one of {LAYER_FIELDS} or 'spectrum.g[i]', 'spectrum.tau_s[i]'")
        layer = self[m.group(1)]
        if m.group(3):
            terms = getattr(layer.spectrum, m.group(3))
            k = int(m.group(4))
            if k >= len(terms):
                raise ParameterError(
                    f"{path!r}: layer {layer.name!r} has {len(terms)} spectrum terms")
            return layer, m.group(3), k
        return layer, m.group(2), None

    def get(self, path) -> float:
        """The value at a parameter path, e.g. ``"dermis.X1"``."""
        layer, key, k = self._parse(path)
        return getattr(layer.spectrum, key)[k] if k is not None else getattr(layer, key)

    def replace(self, values) -> Skin:
        """A copy with the values at the given paths replaced (``{path: value}``).

        Parameters
        ----------
        values : mapping
            Parameter paths and their new values.

        Returns
        -------
        Skin
        """
        layers = list(self.layers)
        for path, value in dict(values).items():
            layer, key, k = self._parse(path)
            i = self.index(layer.name)
            if k is None:
                layers[i] = replace(layers[i], **{key: value})
            else:
                spec = layers[i].spectrum
                terms = list(getattr(spec, key))
                terms[k] = value
                layers[i] = replace(layers[i], spectrum=replace(spec, **{key: tuple(terms)}))
            self = Skin(tuple(layers), self.bottom)  # noqa: PLW0642 (validated at each step)
        return self

    def parameters(self) -> dict:
        """Every numeric parameter by its path, top layer first.

        Returns
        -------
        dict
            ``{"dermis.thickness": 1.0, "dermis.X1": 0.08, ...}``.
        """
        out = {}
        for layer in self.layers:
            for key in LAYER_FIELDS:
                out[f"{layer.name}.{key}"] = getattr(layer, key)
            for key in ("g", "tau_s"):
                for k, v in enumerate(getattr(layer.spectrum, key)):
                    out[f"{layer.name}.spectrum.{key}[{k}]"] = v
        return out

    def two_layer_values(self) -> dict:
        """``x1d, x1h, x2d, x2h, t_d, t_h, prestretch`` of a dermis-over-hypodermis
        skin, for what is built on the paper's two layers (the simulated spaces).

        Raises
        ------
        ParameterError
            If the skin is not exactly a dermis over a hypodermis with one pre-stretch.
        """
        if self.names != ("dermis", "hypodermis"):
            raise ParameterError(
                f"this needs the two-layer skin (dermis, hypodermis), not the layers "
                f"{list(self.names)}")
        d, h = self.layers
        if d.prestretch != h.prestretch:
            raise ParameterError("this needs one pre-stretch for both layers")
        return dict(x1d=d.X1, x1h=h.X1, x2d=d.X2, x2h=h.X2, t_d=d.thickness,
                    t_h=h.thickness, prestretch=d.prestretch)

    # ----------------------------------------------------------- round trips
    def to_dict(self) -> dict:
        """Plain JSON/YAML-able values: ``{"layers": [...], "bottom": ...}``."""
        return {"layers": [layer.to_dict() for layer in self.layers], "bottom": self.bottom}

    @classmethod
    def from_dict(cls, data, source="skin") -> Skin:
        """Build from :meth:`to_dict`'s form; errors name ``source`` and the key.

        Parameters
        ----------
        data : mapping
            ``{"layers": [{name, thickness, X1, ...}, ...], "bottom": ...}``.
        source : str
            What the data came from (a file name), for the error messages.

        Returns
        -------
        Skin
        """
        if not isinstance(data, dict):
            raise ParameterError(f"{source}: a skin is a mapping with 'layers', not {data!r}")
        unknown = set(data) - {"layers", "bottom"}
        if unknown:
            raise ParameterError(f"{source}: unknown key(s) {sorted(unknown)}; "
                                 "a skin has 'layers' and 'bottom'")
        if not isinstance(data.get("layers"), (list, tuple)):
            raise ParameterError(f"{source}: 'layers' must be a list of layers, top first")
        layers = []
        known = set(Layer.__dataclass_fields__)
        for k, entry in enumerate(data["layers"]):
            where = f"{source}: layers[{k}]"
            if not isinstance(entry, dict):
                raise ParameterError(f"{where} must be a mapping, not {entry!r}")
            if set(entry) - known:
                raise ParameterError(f"{where}: unknown key(s) {sorted(set(entry) - known)}; "
                                     f"known: {sorted(known)}")
            missing = {"name", "thickness", "X1"} - set(entry)
            if missing:
                raise ParameterError(f"{where}: missing {sorted(missing)}")
            try:
                layers.append(Layer(**entry))
            except (ParameterError, TypeError) as err:
                raise ParameterError(f"{where}: {err}") from None
        try:
            return cls(tuple(layers), data.get("bottom", "fixed"))
        except ParameterError as err:
            raise ParameterError(f"{source}: {err}") from None

    def to_json(self) -> str:
        """The skin as a JSON text."""
        return json.dumps(self.to_dict(), indent=2)

    @classmethod
    def read(cls, path) -> Skin:
        """Read a skin from a YAML (``.yaml``, ``.yml``) or JSON file.

        Parameters
        ----------
        path : str or Path

        Returns
        -------
        Skin
        """
        import yaml

        path = Path(path)
        try:
            text = path.read_text(encoding="utf-8")
        except OSError as err:
            raise ParameterError(f"{path}: cannot read the skin ({err.strerror})") from None
        try:
            data = json.loads(text) if path.suffix == ".json" else yaml.safe_load(text)
        except (ValueError, yaml.YAMLError) as err:
            raise ParameterError(f"{path}: not valid {'JSON' if path.suffix == '.json' else 'YAML'} "
                                 f"({str(err).splitlines()[0]})") from None
        if isinstance(data, dict) and "skin" in data and "layers" not in data:
            data = data["skin"]
        return cls.from_dict(data, source=str(path))

    def write(self, path) -> Path:
        """Write the skin as YAML or JSON (by the suffix), atomically.

        Parameters
        ----------
        path : str or Path

        Returns
        -------
        Path
        """
        import yaml

        from .._files import atomic_output

        path = Path(path)
        text = (self.to_json() if path.suffix == ".json"
                else yaml.safe_dump(self.to_dict(), sort_keys=False))
        with atomic_output(path) as tmp:
            tmp.write_text(text, encoding="utf-8")
        return path


@dataclass(frozen=True)
class Probe:
    """A suction probe: its aperture diameter in mm (Cutometers: 2, 4, 6, 8).

    Examples
    --------
    >>> Probe(6).radius_mm
    3.0
    """

    aperture_mm: float

    def __post_init__(self):
        a = _number(self.aperture_mm, "probe aperture_mm")
        if not 0 < a <= 50:
            raise ParameterError(f"probe aperture_mm must lie in (0, 50] mm, not {a:g}")
        object.__setattr__(self, "aperture_mm", a)

    @property
    def radius_mm(self) -> float:
        """Aperture radius ``a`` (mm)."""
        return self.aperture_mm / 2


@dataclass(frozen=True)
class Ramp:
    """A quasi-static suction ramp from 0 to ``max_mbar`` in steps of ``step_mbar``
    (the paper's: 0 to 100 mbar by 2).

    Examples
    --------
    >>> Ramp(10, 5).pressures_mbar.tolist()
    [0.0, 5.0, 10.0]
    """

    max_mbar: float = 100.0
    step_mbar: float = 2.0

    def __post_init__(self):
        top = _number(self.max_mbar, "ramp max_mbar")
        step = _number(self.step_mbar, "ramp step_mbar")
        if not 0 < top <= 1000:
            raise ParameterError(f"ramp max_mbar must lie in (0, 1000] mbar, not {top:g}")
        if not 0 < step <= top:
            raise ParameterError(f"ramp step_mbar must lie in (0, max_mbar], not {step:g}")
        object.__setattr__(self, "max_mbar", top)
        object.__setattr__(self, "step_mbar", step)

    @property
    def pressures_mbar(self) -> np.ndarray:
        """The ramp's pressures, 0 first, ``max_mbar`` last."""
        n = int(round(self.max_mbar / self.step_mbar))
        p = np.linspace(0.0, n * self.step_mbar, n + 1)
        if p[-1] < self.max_mbar * (1 - 1e-12):
            p = np.append(p, self.max_mbar)
        p[-1] = self.max_mbar
        return p
