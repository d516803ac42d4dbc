"""The standard Cutometer parameters of a time curve: Ue ... Ua and R0-R9 (mode 1), and
maximal and residual deformation and hysteresis (mode 2).

Definitions (mode 1, one row per cycle; deflections in mm)
----------------------------------------------------------
Readings of cycle k, each a deflection of the file (linearly interpolated between
samples at a time between them) minus the cycle's baseline ``b_k``:

* ``b_k``: 0 for the first cycle (the device zeroes before the first suction: the
  file's zero), and for later cycles the deflection of the last sample before the
  onset (the end of the previous off time), so that every cycle's row describes
  that cycle's own response, comparable with the first;
* ``Ue``, immediate deformation: ``ue_time_s`` (0.1 s by default) after the suction
  onset;
* ``Uf``, final deformation: the last sample of the hold (the end of the suction);
* ``Uv = Uf - Ue``, the delayed deformation (creep);
* ``Ur``, immediate retraction: ``Uf`` minus the deflection ``ue_time_s`` after the
  release onset (the first sample below the hold): the same reading time as Ue, so
  that a linear solid gives ``Ur ~ Ue``;
* ``Ua``, total recovery: ``Uf`` minus the deflection at the end of the off time (the
  last sample before the next onset, or the file's last).

The onset is the first sample after the pressure last sat at the off level (see
:mod:`skinsuction.measured._timecurve`).  Then

====  ===============  ====  ===============
R0    Uf               R5    Ur / Ue
R1    Uf - Ua          R6    Uv / Ue
R2    Ua / Uf          R7    Ur / Uf
R3    max, last cycle  R8    Ua
R4    min, last cycle  R9    R3 - R0 (cycle 1)
====  ===============  ====  ===============

R3 and R4 are the largest and smallest deflection of the last cycle (onset to the end
of the file), from the file's zero; they, and ``R9 = R3 - R0`` of the *first* cycle
(the "tiring" of the skin over the measurement), are properties of the measurement,
not of a cycle: every row of a curve carries the same R3, R4 and R9.  A reading that
falls after the end of the file is NaN, and so are the R values made from it: Ur if
the file ends less than ``ue_time_s`` after the last release, Ua if the last off time
is shorter than 90 % of the earlier ones' (then Ua would be read early).

Mode 2 (ramp up and down) has no hold at constant suction, so R0-R9 do not apply;
:func:`ramp_parameters` gives per ramp the largest deformation, the residual one when
the suction is back to zero and at the end of the off time, and the hysteresis
(the area between the loading and unloading curves in the (p, deflection) plane).

Examples
--------
A linear solid with an elastic jump of 0.4 mm and a Kelvin-Voigt creep of 0.2 mm with
a time constant of 0.5 s, 3 s of suction, 2 s off, read at 100 Hz:

>>> import numpy as np
>>> from skinsuction.measured._timecurve import TimeCurve, _find_cycles
>>> t = np.round(np.arange(0, 5.5, 0.01), 2)
>>> J = lambda s: np.where(s >= 0, 0.4 + 0.2 * (1 - np.exp(-np.clip(s, 0, None) / 0.5)), 0)
>>> d = J(t - 0.5) - J(t - 3.5)
>>> p = np.where((t >= 0.5) & (t < 3.5), 400.0, 0.0)
>>> c = TimeCurve(6.0, t, p, d, cycles=tuple(_find_cycles(t, p, 0.0)), protocol="mode 1")
>>> r = r_parameters(c).iloc[0]
>>> print(f"Ue {r.Ue:.4f}, Uf {r.Uf:.4f}, R6 {r.R6:.3f}, R5 {r.R5:.3f}, R2 {r.R2:.3f}")
Ue 0.4363, Uf 0.5995, R6 0.374, R5 1.000, R2 0.994
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["R_COLUMNS", "RAMP_COLUMNS", "r_parameters", "ramp_parameters"]

#: The columns of :func:`r_parameters` (deflections in mm, ratios dimensionless).
R_COLUMNS = ("probe_mm", "curve", "cycle", "Ue", "Uv", "Uf", "Ur", "Ua",
             "R0", "R1", "R2", "R3", "R4", "R5", "R6", "R7", "R8", "R9")

#: The columns of :func:`ramp_parameters`.
RAMP_COLUMNS = ("probe_mm", "curve", "cycle", "p_max_mbar", "rate_mbar_s", "Umax",
                "Ures", "Uend", "hysteresis_mbar_mm", "hysteresis_fraction")


def _div(a, b):
    return a / b if b and math.isfinite(b) and b != 0 else math.nan


def r_parameters(curve, ue_time_s: float = 0.1):
    """Ue, Uv, Uf, Ur, Ua (mm) and R0-R9 of every cycle of a mode-1 time curve.

    Parameters
    ----------
    curve : TimeCurve
        A curve of :func:`load_time_curves` whose protocol is ``"mode 1"``.
    ue_time_s : float
        When Ue (after the onset) and the retraction Ur (after the release) are read, s.

    Returns
    -------
    pandas.DataFrame
        One row per cycle, columns :data:`R_COLUMNS` (definitions: module docstring).

    Raises
    ------
    ValueError
        If the curve is not mode 1, or ``ue_time_s`` is not positive or not shorter
        than a hold.
    """
    import pandas as pd

    if not (ue_time_s > 0 and math.isfinite(ue_time_s)):
        raise ValueError(f"the Ue reading time must be a positive number of s, not {ue_time_s!r}")
    if curve.protocol != "mode 1":
        raise ValueError(f"the {curve.label} is {curve.protocol}, not mode 1: R0-R9 need "
                         "cycles at a constant suction"
                         + (" (ramp_parameters gives its ramps)" if curve.protocol == "mode 2"
                            else ""))
    t, d = curve.time_s, curve.deflection_mm
    last = curve.cycles[-1]
    tail = d[last.onset:]
    r3, r4 = float(tail.max()), float(tail.min())
    # the off time of a last cycle is complete if it lasts 90 % of the earlier ones'
    offs = [t[c.end] - t[c.release] for c in curve.cycles[:-1]]
    full_off = 0.9 * float(np.median(offs)) if offs else 0.0
    rows = []
    for c in curve.cycles:
        t_on, t_rel = t[c.onset], t[min(c.release, t.size - 1)]
        if t_on + ue_time_s >= t_rel:
            raise ValueError(f"the Ue reading time {ue_time_s:g} s is not shorter than the "
                             f"hold of cycle {c.index} of the {curve.label} "
                             f"({t_rel - t_on:.3g} s from onset to release)")
        base = 0.0 if c.index == 1 else float(d[c.onset - 1])
        d_f = float(d[c.hold_end])
        ue = float(np.interp(t_on + ue_time_s, t, d)) - base
        uf = d_f - base
        released = c.release < t.size
        ur = (d_f - float(np.interp(t_rel + ue_time_s, t, d))
              if released and t_rel + ue_time_s <= t[c.end] else math.nan)
        complete = c.off is not None and (c is not last or t[c.end] - t_rel >= full_off)
        ua = d_f - float(d[c.end]) if complete else math.nan
        rows.append({"probe_mm": curve.probe_mm, "curve": curve.curve, "cycle": c.index,
                     "Ue": ue, "Uv": uf - ue, "Uf": uf, "Ur": ur, "Ua": ua})
    r0_first = rows[0]["Uf"]
    for r in rows:
        r.update(R0=r["Uf"], R1=r["Uf"] - r["Ua"], R2=_div(r["Ua"], r["Uf"]), R3=r3, R4=r4,
                 R5=_div(r["Ur"], r["Ue"]), R6=_div(r["Uv"], r["Ue"]), R7=_div(r["Ur"], r["Uf"]),
                 R8=r["Ua"], R9=r3 - r0_first)
    return pd.DataFrame(rows, columns=list(R_COLUMNS))


def ramp_parameters(curve):
    """Per ramp of a mode-2 curve: largest and residual deformation and hysteresis.

    Columns (:data:`RAMP_COLUMNS`; deflections in mm from the cycle's baseline, as in
    :func:`r_parameters`): ``p_max_mbar`` the peak; ``rate_mbar_s`` the loading rate
    (slope of the pressure between 10 % and 90 % of the peak); ``Umax`` the largest
    deflection of the cycle; ``Ures`` the deflection when the suction is back at the off
    level; ``Uend`` at the end of the
    off time; ``hysteresis_mbar_mm`` the area between the loading and unloading curves,
    ``-∮ d dp`` from onset to the off level (0 for an elastic solid, positive when
    unloading lags); ``hysteresis_fraction`` that area over the loading's
    ``∫ d dp`` (the share of the work of loading not given back).

    Raises
    ------
    ValueError
        If the curve is not mode 2.
    """
    import pandas as pd
    from scipy.integrate import trapezoid
    from scipy.stats import linregress

    if curve.protocol != "mode 2":
        raise ValueError(f"the {curve.label} is {curve.protocol}, not mode 2 (a ramp up and "
                         "down)")
    t, p, d = curve.time_s, curve.pressure_mbar, curve.deflection_mm
    rows = []
    for c in curve.cycles:
        base = 0.0 if c.index == 1 else float(d[c.onset - 1])
        stop = c.off if c.off is not None else t.size - 1
        # the loop closes at the off level: from the sample before the onset (p ~ 0)
        a = max(c.onset - 1, 0)
        area = -float(trapezoid(d[a:stop + 1], p[a:stop + 1]))
        loading = float(trapezoid(d[a:c.hold_end + 1], p[a:c.hold_end + 1]))
        up = np.arange(c.onset, c.hold_start + 1)
        up = up[(p[up] >= 0.1 * c.level_mbar) & (p[up] <= 0.9 * c.level_mbar)]
        rate = float(linregress(t[up], p[up]).slope) if up.size >= 3 else math.nan
        rows.append({
            "probe_mm": curve.probe_mm, "curve": curve.curve, "cycle": c.index,
            "p_max_mbar": c.level_mbar,
            "rate_mbar_s": rate,
            "Umax": float(d[c.onset:stop + 1].max()) - base,
            "Ures": float(d[c.off]) - base if c.off is not None else math.nan,
            "Uend": float(d[c.end]) - base if c.off is not None else math.nan,
            "hysteresis_mbar_mm": area if c.off is not None else math.nan,
            "hysteresis_fraction": _div(area, loading) if c.off is not None else math.nan,
        })
    return pd.DataFrame(rows, columns=list(RAMP_COLUMNS))
