"""The subject's layer thicknesses: file header lines, study columns, options.

A measured file may give the thicknesses measured on the same site (ultrasound,
OCT) as header lines, and a long study table as columns of the same names::

    # dermis_thickness_mm: 1.3
    # dermis_thickness_sd_mm: 0.1
    # hypodermis_thickness_mm: 3.0

Options (``--dermis-thickness-mm`` ..., defined with the commands in
:mod:`skinsuction.commands`) override the file.  A thickness not given is the
paper's 1 mm, and every output says so (:meth:`Geometry.assumptions`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

from ._types import MeasuredDataError

__all__ = ["GEOMETRY_KEYS", "Geometry", "DEFAULT_LAYERS_MM", "geometry_of",
           "check_geometry_metadata"]

#: The paper's layers (mm): the rays of the shipped space.
DEFAULT_LAYERS_MM = (1.0, 1.0)


@dataclass(frozen=True)
class Geometry:
    """Layer thicknesses of one measurement (mm), given or assumed.

    ``given`` names the thicknesses the user measured (``"t_d"``, ``"t_h"``); the
    others are the paper's 1 mm, an assumption stated in every output
    (:meth:`assumptions`).  ``sd`` holds their standard deviations (mm) where given.

    Examples
    --------
    >>> g = Geometry(1.3, 1.0, given=("t_d",), sd={"t_d": 0.1})
    >>> g.is_default, g.assumptions()
    (False, ["hypodermis thickness assumed 1 mm over a fixed bottom (the paper's; not given)"])
    """

    t_d: float = 1.0
    t_h: float = 1.0
    given: tuple = ()
    sd: dict = field(default_factory=dict)

    @property
    def is_default(self) -> bool:
        return (math.isclose(self.t_d, DEFAULT_LAYERS_MM[0])
                and math.isclose(self.t_h, DEFAULT_LAYERS_MM[1]))

    def assumptions(self) -> list:
        """One sentence per thickness that was not given."""
        out = []
        if "t_d" not in self.given:
            out.append(f"dermis thickness assumed {self.t_d:g} mm (the paper's; not given)")
        if "t_h" not in self.given:
            out.append(f"hypodermis thickness assumed {self.t_h:g} mm over a fixed bottom "
                       "(the paper's; not given)")
        return out

    def shifted(self, key: str, delta: float) -> "Geometry":
        """The same geometry with thickness ``key`` moved by ``delta`` mm, taken as exact.

        A point of a sensitivity (the fit at ``t +- sd``): it keeps no sd, whose
        brackets would be solved at ``t +- 2 sd`` and read by nothing (for a 0.41 mm
        dermis under the 6 mm probe that was 127 of a ramp's 516 CPU-s).

        >>> Geometry(1.3, 1.0, given=("t_d",), sd={"t_d": 0.1}).shifted("t_d", -0.1).sd
        {}
        """
        return replace(self, sd={}, **{key: getattr(self, key) + delta})

    def to_dict(self) -> dict:
        return {"dermis_thickness_mm": self.t_d, "hypodermis_thickness_mm": self.t_h,
                "given": list(self.given),
                "dermis_thickness_sd_mm": self.sd.get("t_d"),
                "hypodermis_thickness_sd_mm": self.sd.get("t_h"),
                "assumptions": self.assumptions()}



#: (key of the file, Geometry field, plausible range in mm, what it is)
GEOMETRY_KEYS = {
    "dermis_thickness_mm": ("t_d", (0.1, 5.0), "dermis (with the epidermis)"),
    "hypodermis_thickness_mm": ("t_h", (0.1, 60.0), "hypodermis"),
}
SD_KEYS = {"dermis_thickness_sd_mm": "dermis_thickness_mm",
           "hypodermis_thickness_sd_mm": "hypodermis_thickness_mm"}
#: a thickness above this many mm is read as a unit mistake (µm)
MICROMETRE_HINT_ABOVE = 100.0


def _value(path, line, key, text) -> float:
    try:
        v = float(str(text).strip())
    except ValueError:
        raise MeasuredDataError(path, line, key, f"{key} {str(text)!r} is not a number "
                                "(give the thickness in mm)") from None
    if not math.isfinite(v):
        raise MeasuredDataError(path, line, key, f"{key} {text!r} is not finite")
    return v


def _check_thickness(path, line, key, v) -> None:
    field_, (lo, hi), what = GEOMETRY_KEYS[key]
    if v <= 0:
        raise MeasuredDataError(path, line, key, f"{key} {v:g} must be positive (mm)")
    if v > MICROMETRE_HINT_ABOVE:
        raise MeasuredDataError(path, line, key, f"{key} {v:g} looks like µm, not mm "
                                f"(divide by 1000: {v / 1000:g} mm)")
    if not lo <= v <= hi:
        raise MeasuredDataError(path, line, key, f"{key} {v:g} mm is not a plausible "
                                f"thickness of the {what} ({lo:g}-{hi:g} mm)")


def check_geometry_metadata(path, metadata: dict, lines: dict | None = None) -> dict:
    """The thicknesses of a file's ``key: value`` lines (or a study's columns), checked.

    Returns ``{key: float}`` for the geometry keys present; raises
    :class:`MeasuredDataError` naming the file, the line and the key for a bad one
    (not a number, not positive, µm instead of mm, implausible, an sd without its
    thickness or not below it).

    >>> check_geometry_metadata("f.csv", {"dermis_thickness_mm": "1.3"})
    {'dermis_thickness_mm': 1.3}
    >>> check_geometry_metadata("f.csv", {"dermis_thickness_mm": "1300"}, {"dermis_thickness_mm": 2})
    Traceback (most recent call last):
    ...
    skinsuction.measured.MeasuredDataError: f.csv, line 2, column 'dermis_thickness_mm': dermis_thickness_mm 1300 looks like µm, not mm (divide by 1000: 1.3 mm)
    """
    lines = lines or {}
    out = {}
    for key in GEOMETRY_KEYS:
        if key in metadata and str(metadata[key]).strip() != "":
            v = _value(path, lines.get(key), key, metadata[key])
            _check_thickness(path, lines.get(key), key, v)
            out[key] = v
    for sd_key, key in SD_KEYS.items():
        if sd_key in metadata and str(metadata[sd_key]).strip() != "":
            line = lines.get(sd_key)
            v = _value(path, line, sd_key, metadata[sd_key])
            if key not in out:
                raise MeasuredDataError(path, line, sd_key, f"{sd_key} is given without "
                                        f"{key}")
            if v < 0 or v >= out[key]:
                raise MeasuredDataError(path, line, sd_key, f"{sd_key} {v:g} must lie in "
                                        f"0 <= sd < {key} ({out[key]:g} mm)")
            out[sd_key] = v
    return out


def geometry_of(data, *, dermis_thickness_mm=None, hypodermis_thickness_mm=None,
                dermis_thickness_sd_mm=None, hypodermis_thickness_sd_mm=None):
    """``(Geometry, warnings)`` of loaded data: options first, then the file's lines.

    Parameters
    ----------
    data : MeasuredData
        Its ``metadata`` may hold the geometry keys (checked by the loader).
    dermis_thickness_mm, hypodermis_thickness_mm : float, optional
        Override the file (a warning says so when they differ).
    dermis_thickness_sd_mm, hypodermis_thickness_sd_mm : float, optional

    Examples
    --------
    >>> from skinsuction.measured import MeasuredData
    >>> g, w = geometry_of(MeasuredData("f.csv", (), {"dermis_thickness_mm": "1.3"}))
    >>> g.t_d, g.t_h, g.given, len(g.assumptions())
    (1.3, 1.0, ('t_d',), 1)
    """
    path = getattr(data, "path", "<options>")
    meta = check_geometry_metadata(path, dict(getattr(data, "metadata", {}) or {}))
    options = {"dermis_thickness_mm": dermis_thickness_mm,
               "hypodermis_thickness_mm": hypodermis_thickness_mm,
               "dermis_thickness_sd_mm": dermis_thickness_sd_mm,
               "hypodermis_thickness_sd_mm": hypodermis_thickness_sd_mm}
    given_opts = {k: float(v) for k, v in options.items() if v is not None}
    warnings = []
    if given_opts:
        checked = check_geometry_metadata("options", {
            **{k: v for k, v in meta.items() if k not in given_opts
               and SD_KEYS.get(k) not in given_opts},
            **given_opts})
        for k, v in given_opts.items():
            if k in meta and not math.isclose(meta[k], v):
                warnings.append(f"--{k.replace('_', '-')} {v:g} overrides the file's "
                                f"{k}: {meta[k]:g}")
        meta = checked
    t_d = meta.get("dermis_thickness_mm")
    t_h = meta.get("hypodermis_thickness_mm")
    given = tuple(k for k, v in (("t_d", t_d), ("t_h", t_h)) if v is not None)
    sd = {k: meta[s] for k, s in (("t_d", "dermis_thickness_sd_mm"),
                                   ("t_h", "hypodermis_thickness_sd_mm")) if s in meta}
    geometry = Geometry(t_d=1.0 if t_d is None else t_d, t_h=1.0 if t_h is None else t_h,
                        given=given, sd=sd)
    return geometry, warnings
