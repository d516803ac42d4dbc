"""Load and check measured suction curves M(p) (CSV files).

File format
-----------
UTF-8 text (a byte-order mark is allowed), comma-separated, one header line::

    # subject: S01
    # site: forearm
    probe_mm,pressure_mbar,deflection_mm,curve
    6,0,0.000,A
    6,2,0.031,A
    ...

* Columns ``probe_mm`` (aperture diameter, mm), ``pressure_mbar`` (suction,
  positive, mbar) and ``deflection_mm`` (apex deflection into the aperture, mm)
  are required; ``curve`` (replicate id, any text) is optional.  No other column
  is allowed; the order of the columns is free.
* Lines starting with ``#`` are comments, kept in ``MeasuredData.comments``;
  ``# key: value`` comments also go to ``MeasuredData.metadata`` (a later key
  overrides an earlier one).  Blank lines are ignored.
* The subject's layer thicknesses, measured on the same site (ultrasound, OCT),
  may be given as ``# dermis_thickness_mm: 1.3`` and ``# hypodermis_thickness_mm:
  3.0``, each with an optional standard deviation (``# dermis_thickness_sd_mm:
  0.1``); a study table may give them as columns of the same names.  They are
  checked (a number, positive, plausible, not µm: a located error otherwise) and
  used by ``identify``, ``diagnose`` and ``study`` (:func:`geometry_of`); a
  thickness not given is the paper's 1 mm, stated in every output.
* One file may hold several probes and several curves per probe.  A curve is
  the set of rows with the same (``probe_mm``, ``curve``); without a ``curve``
  column every probe has exactly one curve.  Within a curve the pressures must
  strictly increase down the file.

Every rejection raises :class:`MeasuredDataError` (a ``ValueError``) with a
one-line message naming the file, the line (1-based, counting every line of the
file) and, where it applies, the column.  The checks, in this order:

1. the file can be read and is UTF-8;
2. header: comma-separated, no missing, unknown or repeated column;
3. every row: as many fields as the header; numbers in plain decimal notation
   (``1``, ``-0.5``, ``2e-3``), finite; ``probe_mm > 0``; ``curve`` not empty;
4. every curve: at least 2 points, pressures strictly increasing (a drop
   suggests two curves without a ``curve`` column), then the unit rules below;
5. against the simulated space, if given: the probe diameter is one of
   ``available_probes`` (to 1e-6 mm); the pressures lie in
   ``pressure_range_mbar`` (to 1e-9 mbar).

Unit and plausibility rules, per curve (a Cutometer applies at most about
500 mbar, and a dome cannot rise beyond its aperture):

* pressures below zero: suction must be given as positive mbar (checked first:
  0, -50, -100 mbar is a sign, not a new curve);
* largest pressure above 1000 "mbar": looks like Pa (1 mbar = 100 Pa);
* largest pressure above 0 but at most 1 "mbar": looks like bar or kPa
  (100 mbar = 0.1 bar = 10 kPa);
* no pressure above 0: a curve needs suction;
* largest pressure at most 20 mbar: a *warning* only (``MeasuredData.warnings``):
  protocols apply 50-500 mbar and the file may be in kPa, but a low-pressure
  protocol is possible;
* largest |deflection| above the aperture diameter (or 20 mm): looks like µm;
* all deflections 0: no dome was measured;
* largest |deflection| below 1/1000 of the aperture diameter (6 µm under the
  6 mm probe, 2 µm under the 2 mm one) or 0.001 mm: looks like metres;
* deflections all <= 0 with some < 0: wrong sign (positive into the aperture);
* a deflection at 0 mbar above 10 % of the largest and 0.01 mm: the curve must
  be zeroed there (the instrument zeroes at 0 mbar);
* a fall of the deflection below an earlier one by more than a quarter of the
  curve's span, 0.02 mm and (on 20 points or more) 8 times the noise sd the curve
  itself shows in its third differences, or a falling trend: it must grow with the
  pressure (noise makes only small falls; a small 2 mm curve of stiff skin with 5 µm
  of noise falls by 20-25 µm, a smooth falling curve has little noise).

Either kind of file, read once, the kind decided by its header (a ``time_s``
column): :func:`read_measurement`.  Checks against a space learnt after reading
(its reach depends on the file's layers): :func:`check_against_space`.

Time curves (Cutometer mode 1 and mode 2, columns ``probe_mm, time_s, pressure_mbar,
deflection_mm``) are read by :func:`load_time_curves`, which finds the phases of the
suction, the deflection's resolution and the noise; :func:`r_parameters` gives the
standard R0-R9 of a mode-1 curve (:mod:`skinsuction.measured._timecurve`,
:mod:`skinsuction.measured._phases`, :mod:`skinsuction.measured._rparams`,
``docs/time_curves.md``); :func:`grid_step` reads the deflection's resolution.

Sizes: at most 2 000 points per curve, 2 000 000 lines and 256 MB per file, so
that a wrong file fails fast instead of filling the memory.

Examples
--------
>>> import pathlib, tempfile
>>> path = pathlib.Path(tempfile.mkdtemp()) / "s01.csv"
>>> _ = path.write_text("# subject: S01\\nprobe_mm,pressure_mbar,deflection_mm\\n"
...                     "6,0,0\\n6,50,0.4\\n6,100,0.7\\n", encoding="utf-8")
>>> data = load_measured(path, available_probes=[2, 6], pressure_range_mbar=(0, 100))
>>> data.metadata["subject"], data.probes
('S01', (6.0,))
>>> data.curve(6).deflection_mm.tolist()
[0.0, 0.4, 0.7]
>>> _ = path.write_text("probe_mm,pressure_mbar,deflection_mm\\n6,0,0\\n6,5000,400\\n")
>>> load_measured(path)  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
skinsuction.measured.MeasuredDataError: ...s01.csv, line 3, column 'pressure_mbar': largest pressure 5000 mbar looks like Pa, not mbar (1 mbar = 100 Pa; a Cutometer applies at most about 500 mbar)
"""

from ._checks import (
    APERTURE_FLOOR,
    APERTURE_LIMIT,
    BAR_AT_MOST_MBAR,
    LOW_PRESSURE_MBAR,
    M_BELOW_MM,
    PA_ABOVE_MBAR,
    UM_ABOVE_MM,
)
from ._geometry import DEFAULT_LAYERS_MM, GEOMETRY_KEYS, SD_KEYS, Geometry, check_geometry_metadata, geometry_of
from ._load import StudyEntry, check_against_space, load_measured, load_table
from ._read import read_measurement
from ._phases import grid_step
from ._rparams import R_COLUMNS, RAMP_COLUMNS, r_parameters, ramp_parameters
from ._timecurve import (
    DEVICE_MAX_MBAR,
    MIN_SAMPLES,
    TIME_OPTIONAL_COLUMNS,
    TIME_REQUIRED_COLUMNS,
    Cycle,
    MeasuredTimeData,
    TimeCurve,
    is_time_curve_file,
    load_time_curves,
)
from ._types import (
    MAX_FILE_BYTES,
    MAX_POINTS_PER_CURVE,
    MAX_ROWS_PER_FILE,
    OPTIONAL_COLUMNS,
    REQUIRED_COLUMNS,
    MeasuredCurve,
    MeasuredData,
    MeasuredDataError,
)

# the public classes are documented (and shown in tracebacks) under this package
for _cls in (MeasuredCurve, MeasuredData, MeasuredDataError, StudyEntry, Cycle, TimeCurve,
             MeasuredTimeData):
    _cls.__module__ = __name__
del _cls

__all__ = [
    "MeasuredDataError", "MeasuredCurve", "MeasuredData", "load_measured", "StudyEntry",
    "load_table", "read_measurement", "check_against_space", "REQUIRED_COLUMNS", "OPTIONAL_COLUMNS", "MAX_POINTS_PER_CURVE",
    "MAX_ROWS_PER_FILE", "MAX_FILE_BYTES", "PA_ABOVE_MBAR", "BAR_AT_MOST_MBAR", "UM_ABOVE_MM",
    "M_BELOW_MM", "APERTURE_LIMIT", "APERTURE_FLOOR", "LOW_PRESSURE_MBAR",
    "GEOMETRY_KEYS", "SD_KEYS", "Geometry", "DEFAULT_LAYERS_MM", "check_geometry_metadata",
    "geometry_of",
    "load_time_curves", "is_time_curve_file", "TimeCurve", "Cycle", "MeasuredTimeData",
    "TIME_REQUIRED_COLUMNS", "TIME_OPTIONAL_COLUMNS", "MIN_SAMPLES", "DEVICE_MAX_MBAR", "grid_step",
    "r_parameters", "ramp_parameters", "R_COLUMNS", "RAMP_COLUMNS",
]
