"""What a design question is made of: the plausible skins, the candidate designs, the question.

A :class:`Box` of skins is drawn (seeded) into a table, or a table is read from a
study (``curves.parquet``: its estimates and layers).  A :class:`Design` is one
candidate measurement: the probes, a pressure ramp to a suction, the noise and the
Cutometer's 0.01 mm resolution, which layer thicknesses are given and how well.
A :class:`Question` says what the study must answer: parameters to a precision,
causes to tell apart.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

__all__ = ["Box", "Design", "Question", "designs_from", "skins_from_table", "CAUSE_COLUMNS",
           "relative_halfwidth"]

#: A protocol's timing defaults: mode 1 (on s, off s, cycles), mode 2 (rate, mbar/s)
TIMING = {"ramp": (), "mode1": (3.0, 3.0, 2.0), "mode2": (25.0,)}

#: Each cause's drawn column: its parameter (as the cause's space reads it).
CAUSE_COLUMNS = {"strain_stiffening": "x2d_ratio", "pre_tension": "lambda0",
                 "hypodermis_thickness": "t_h_cause_mm", "dermis_thickness": "t_d_cause_mm"}


def relative_halfwidth(symbol: str, value: float, interval) -> tuple:
    """``(half-width, bounded)``: the interval's larger side over the value (lambda0:
    over its strain, lambda0 - 1); unbounded (inf) where an end is open.

    >>> from types import SimpleNamespace as NS
    >>> relative_halfwidth("X1h", 2.0, NS(lower=1.5, upper=2.6, lower_open=False, upper_open=False))
    (0.3, True)
    >>> relative_halfwidth("lambda0", 1.1, NS(lower=1.05, upper=1.12, lower_open=False,
    ...                                       upper_open=True))
    (inf, False)
    """
    if interval is None:
        return math.nan, False
    shift = 1.0 if symbol == "lambda0" else 0.0
    v, lo, hi = value - shift, interval.lower - shift, interval.upper - shift
    bounded = not (interval.lower_open or interval.upper_open)
    if not bounded:
        return math.inf, False
    return round(float(max(hi / v - 1.0, 1.0 - lo / v)), 12), True


def _range(value, key) -> tuple:
    lo, hi = (float(value), float(value)) if np.isscalar(value) else map(float, value)
    if not (0 < lo <= hi) or not math.isfinite(hi):
        raise ValueError(f"box: {key} must be a positive range lo <= hi, got {value!r}")
    return lo, hi


@dataclass(frozen=True)
class Box:
    """Plausible skins: every modulus and the hypodermis log-uniform, the dermis uniform.

    Parameters
    ----------
    x1d_mpa : (lo, hi)
        Default 0.007-0.09 MPa: forearm E = 129 ± 88 kPa (X1d = E/6) up to the
        paper's own fit (0.09).
    x1h_ratio : (lo, hi)
        X1h/X1d.
    t_d_mm, t_h_mm : (lo, hi)
        The layers (default the paper's 1 mm each).
    causes : dict name -> (lo, hi)
        Each cause's parameter: X2d/X1d, lambda0, t_h or t_d (mm) of the thickness
        causes.
    g, tau_s : (lo, hi)
        The one-term relaxation spectrum of a mode 1 or mode 2 design (log-uniform;
        default g 0.1-1, tau 0.1-1 s: the creep of forearm skin within 2-3 s holds).

    Examples
    --------
    >>> skins = Box().draw(3, seed=0)
    >>> list(skins.columns)[:4], len(skins)
    (['skin', 'x1d_mpa', 'x1h_ratio', 't_d_mm'], 3)
    >>> bool(skins["x1d_mpa"].between(0.007, 0.09).all())
    True
    """

    x1d_mpa: tuple = (0.007, 0.09)
    x1h_ratio: tuple = (0.003, 0.3)
    t_d_mm: tuple = (1.0, 1.0)
    t_h_mm: tuple = (1.0, 1.0)
    causes: dict = field(default_factory=lambda: {
        "strain_stiffening": (2.0, 30.0), "pre_tension": (1.03, 1.15),
        "hypodermis_thickness": (2.0, 6.0), "dermis_thickness": (0.6, 1.6)})
    g: tuple = (0.1, 1.0)
    tau_s: tuple = (0.1, 1.0)

    def __post_init__(self):
        for key in ("x1d_mpa", "x1h_ratio", "t_d_mm", "t_h_mm", "g", "tau_s"):
            object.__setattr__(self, key, _range(getattr(self, key), key))
        unknown = sorted(set(self.causes) - set(CAUSE_COLUMNS))
        if unknown:
            raise ValueError(f"box: unknown causes {unknown}; known: {sorted(CAUSE_COLUMNS)}")
        object.__setattr__(self, "causes", {k: _range(v, f"causes.{k}")
                                            for k, v in self.causes.items()})

    @classmethod
    def from_config(cls, section: dict | None) -> "Box":
        """From the config's ``design.box`` (its keys are the fields)."""
        section = dict(section or {})
        unknown = sorted(set(section) - set(cls.__dataclass_fields__))
        if unknown:
            raise ValueError(f"design.box: unknown keys {unknown}")
        return cls(**section)

    def draw(self, n: int, seed: int = 0) -> pd.DataFrame:
        """``n`` skins (one row each), with every cause's parameter drawn too."""
        rng = np.random.default_rng(seed)

        def log_uniform(r):
            return 10 ** rng.uniform(math.log10(r[0]), math.log10(r[1]), n)

        out = {"skin": np.arange(n), "x1d_mpa": log_uniform(self.x1d_mpa),
               "x1h_ratio": log_uniform(self.x1h_ratio),
               "t_d_mm": np.round(rng.uniform(*self.t_d_mm, n), 2),
               "t_h_mm": np.round(log_uniform(self.t_h_mm), 2)}
        for name, r in self.causes.items():
            draw = rng.uniform(*r, n) if name == "pre_tension" else log_uniform(r)
            out[CAUSE_COLUMNS[name]] = draw
        # the spectrum from a stream of its own: the skins of a seed stay those drawn
        # before it was added
        spectrum = np.random.default_rng([seed, 1])
        for key, col in (("g", "g_1"), ("tau_s", "tau_1_s")):
            lo, hi = getattr(self, key)
            out[col] = 10 ** spectrum.uniform(math.log10(lo), math.log10(hi), n)
        return pd.DataFrame(out)


def skins_from_table(path) -> pd.DataFrame:
    """The skins of a study's table: its estimates (``x1d_mpa``, ``x1h_mpa``) and layers.

    Parameters
    ----------
    path : path-like
        ``curves.parquet`` of ``skinsuction study`` or a CSV with those columns
        (``dermis_thickness_mm``, ``hypodermis_thickness_mm`` optional: 1 mm).

    Returns
    -------
    pandas.DataFrame
        As :meth:`Box.draw` (without the causes' columns): rows without both
        estimates are dropped.

    Raises
    ------
    ValueError
        If the table lacks the estimate columns, or has no row with both.
    """
    path = Path(path)
    df = pd.read_parquet(path) if path.suffix == ".parquet" else pd.read_csv(path)
    missing = [c for c in ("x1d_mpa", "x1h_mpa") if c not in df]
    if missing:
        raise ValueError(f"{path}: no column {', '.join(missing)} (a study's curves.parquet "
                         "or a CSV of x1d_mpa, x1h_mpa and optionally the layers)")
    ok = df[["x1d_mpa", "x1h_mpa"]].notna().all(axis=1) & (df["x1d_mpa"] > 0)
    if not ok.any():
        raise ValueError(f"{path}: no row with both x1d_mpa and x1h_mpa")
    d = df[ok]
    return pd.DataFrame({
        "skin": np.arange(len(d)), "x1d_mpa": d["x1d_mpa"].to_numpy(float),
        "x1h_ratio": (d["x1h_mpa"] / d["x1d_mpa"]).to_numpy(float),
        "t_d_mm": d.get("dermis_thickness_mm", pd.Series(1.0, index=d.index)).fillna(1.0)
        .to_numpy(float),
        "t_h_mm": d.get("hypodermis_thickness_mm", pd.Series(1.0, index=d.index)).fillna(1.0)
        .to_numpy(float)})


@dataclass(frozen=True)
class Design:
    """One candidate measurement: a pressure ramp on one or more probes.

    Parameters
    ----------
    probes_mm : tuple of float
        2, 4, 6 and/or 8 mm.
    max_mbar : float
        The ramp's top (0 to ``max_mbar`` in ``step_mbar`` steps).
    noise_um : float
        Noise sd of one deflection (µm).
    resolution_mm : float
        The device's reading step (0.01 mm): a rounding error of sd step/sqrt(12).
    given : dict
        Thicknesses given (``t_d``, ``t_h``) -> their sd (mm).
    step_mbar : float
        The ramp's pressure step.
    protocol : {"ramp", "mode1", "mode2"}
        A quasi-static ramp (the paper's), or the Cutometer's time curves: mode 1
        holds ``max_mbar`` and releases it (``timing`` = on s, off s, cycles; default
        3, 3, 2), mode 2 ramps up to it and down (``timing`` = rate in mbar/s;
        default 25), both recorded at ``sample_hz``.
    timing : tuple
    sample_hz : float

    Examples
    --------
    >>> d = Design((2.0, 6.0), 300.0, given={"t_d": 0.1})
    >>> d.name, d.points, round(d.sigma_um(0.3), 2)
    ('2+6 mm, 300 mbar, t_d given', 151, 3.52)
    >>> Design((6.0,), 450.0, protocol="mode1").name
    '6 mm, mode 1 at 450 mbar (3 s on, 3 s off, 2 cycles)'
    """

    probes_mm: tuple
    max_mbar: float = 100.0
    noise_um: float = 2.0
    resolution_mm: float = 0.01
    given: dict = field(default_factory=dict)
    step_mbar: float = 2.0
    protocol: str = "ramp"
    timing: tuple = ()
    sample_hz: float = 100.0

    def __post_init__(self):
        if self.protocol not in TIMING:
            raise ValueError(f"design: the protocol must be one of {sorted(TIMING)}, not "
                             f"{self.protocol!r}")
        timing = tuple(float(x) for x in (self.timing or TIMING[self.protocol]))
        if len(timing) != len(TIMING[self.protocol]) or not all(x > 0 for x in timing):
            raise ValueError(f"design: {self.protocol} timing must be "
                             f"{len(TIMING[self.protocol])} positive numbers, got {self.timing}")
        object.__setattr__(self, "timing", timing)
        if self.protocol != "ramp" and not self.sample_hz > 0:
            raise ValueError("design: sample_hz must be > 0")
        probes = tuple(sorted(float(p) for p in self.probes_mm))
        if not probes or any(p not in (2.0, 4.0, 6.0, 8.0) for p in probes):
            raise ValueError(f"design: probes must be among 2, 4, 6, 8 mm, got {self.probes_mm}")
        object.__setattr__(self, "probes_mm", probes)
        if not 0 < self.max_mbar <= 500:
            raise ValueError(f"design: the suction must be in (0, 500] mbar (the Cutometer's "
                             f"range), got {self.max_mbar}")
        bad = sorted(set(self.given) - {"t_d", "t_h"})
        if bad:
            raise ValueError(f"design: only t_d and t_h can be given, not {bad}")
        if self.noise_um < 0 or self.resolution_mm < 0:
            raise ValueError("design: noise and resolution must be >= 0")

    @property
    def name(self) -> str:
        given = " + ".join(f"{k} given" for k in ("t_d", "t_h") if k in self.given)
        probes = f"{'+'.join(f'{p:g}' for p in self.probes_mm)} mm"
        if self.protocol == "mode1":
            on, off, n = self.timing
            load = (f"mode 1 at {self.max_mbar:g} mbar ({on:g} s on, {off:g} s off, "
                    f"{n:g} cycles)")
        elif self.protocol == "mode2":
            load = f"mode 2 to {self.max_mbar:g} mbar ({self.timing[0]:g} mbar/s)"
        else:
            load = f"{self.max_mbar:g} mbar"
        return f"{probes}, {load}" + (f", {given}" if given else "")

    def history(self) -> tuple:
        """``(time_s, pressure_mbar, phase)`` of a mode 1 or mode 2 design, sampled at
        ``sample_hz``; the phase of each sample as the time fits label it (``rest``,
        ``on``, ``release``: the first 0.1 s after a release, ``off``, ``ramp``)."""
        from skinsuction.identify import RELEASE_S
        from skinsuction.viscoelastic import mode1_history, mode2_history

        if self.protocol == "mode1":
            on, off, n = self.timing
            h = mode1_history(self.max_mbar, on_s=on, off_s=off, cycles=int(n))
        elif self.protocol == "mode2":
            h = mode2_history(self.max_mbar, rate_mbar_s=self.timing[0])
        else:
            raise ValueError("a ramp design has no time history")
        t = np.arange(0.0, h.times_s[-1] + 0.5 / self.sample_hz, 1.0 / self.sample_hz)
        p = np.interp(t, h.times_s, h.pressure_mbar)
        if self.protocol == "mode2":
            phase = np.full(t.size, "ramp", dtype=object)
        else:
            rel = np.mod(t - 1e-9, on + off)
            phase = np.where(rel < on, "on", np.where(rel < on + RELEASE_S, "release", "off"))
            phase = phase.astype(object)
        phase[0] = "rest"
        return t, p, phase

    @property
    def points(self) -> int:
        return int(round(self.max_mbar / self.step_mbar)) + 1

    def pressures(self) -> np.ndarray:
        """The loaded points (the 0 mbar point carries no information)."""
        return np.linspace(0.0, self.max_mbar, self.points)[1:]

    def sigma_um(self, model_error_um: float) -> float:
        """The sd of one point: noise, rounding and the spaces' own error."""
        return math.sqrt(self.noise_um ** 2 + (1e3 * self.resolution_mm) ** 2 / 12
                         + model_error_um ** 2)


def designs_from(probe_sets, suctions, *, noise_um=2.0, resolution_mm=0.01, given=None,
                 step_mbar=2.0, protocols=("ramp",), timing=None, sample_hz=100.0) -> list:
    """Every probe set at every suction, in every protocol (``timing``: protocol ->
    its timing, where not the default).

    >>> [d.name for d in designs_from(["2", "2+6"], [100, 500])]
    ['2 mm, 100 mbar', '2 mm, 500 mbar', '2+6 mm, 100 mbar', '2+6 mm, 500 mbar']
    """
    out = []
    for s in probe_sets:
        probes = tuple(float(x) for x in str(s).replace(",", "+").split("+")) \
            if not isinstance(s, (tuple, list)) else tuple(s)
        for protocol in protocols:
            for p in suctions:
                out.append(Design(probes, float(p), noise_um, resolution_mm, dict(given or {}),
                                  step_mbar, protocol, tuple((timing or {}).get(protocol, ())),
                                  sample_hz))
    return out


@dataclass(frozen=True)
class Question:
    """What the study must answer.

    Parameters
    ----------
    precision : dict
        Parameter (``X1d``, ``X1h``, a cause's symbol) -> the largest relative
        half-width of its 95 % interval (0.2: ±20 %), met by ``quantile`` of the skins.
    tell : tuple of str
        Causes to tell apart from one another: each one's attribution ceiling
        against each other, over the skins where it is detectable, at least ``rate``.
    quantile, rate : float

    Examples
    --------
    >>> Question({"X1h": 0.2}, ("pre_tension", "hypodermis_thickness")).text
    'X1h to ±20 % (90 % of skins); tell pre_tension, hypodermis_thickness apart (95 %)'
    """

    precision: dict = field(default_factory=dict)
    tell: tuple = ()
    quantile: float = 0.9
    rate: float = 0.95

    def __post_init__(self):
        for k, v in self.precision.items():
            if not v > 0:
                raise ValueError(f"question: the precision of {k} must be > 0, got {v}")
        bad = sorted(set(self.tell) - set(CAUSE_COLUMNS))
        if bad:
            raise ValueError(f"question: unknown causes {bad}; known: {sorted(CAUSE_COLUMNS)}")
        if not (0 < self.quantile < 1 and 0 < self.rate < 1):
            raise ValueError("question: quantile and rate must be in (0, 1)")
        object.__setattr__(self, "tell", tuple(self.tell))

    @property
    def text(self) -> str:
        parts = [f"{k} to ±{100 * v:g} % ({100 * self.quantile:g} % of skins)"
                 for k, v in self.precision.items()]
        if len(self.tell) > 1:
            parts.append(f"tell {', '.join(self.tell)} apart ({100 * self.rate:g} %)")
        elif self.tell:
            parts.append(f"detect {self.tell[0]}")
        return "; ".join(parts) or "no question: the table only"
