"""The results of ``skinsuction identify``: typed, and their JSON.

:class:`Identification` is what :func:`skinsuction.identify.measured_fit.identify_data`
returns for a pressure ramp, :class:`TimeIdentification` what
:func:`skinsuction.identify.time_curves.identify_time_data` returns for time curves.
Their fields are the top-level entries of ``identification.json``, in its order;
:meth:`~Identification.to_json` gives that dict and :meth:`~Identification.figure`
its figure; :func:`write_identification`, the one writer of both, writes them
(the JSON strict, :func:`skinsuction.results.write_json`: NaN and infinities null).

While callers move to attribute access, ``result["estimate"]``, ``result.get(...)``,
``result.keys()`` and ``"key" in result`` read :meth:`~Identification.to_json`: the
mapping view of the JSON, read-only at the top level.

Examples
--------
>>> r = Identification("0.1.0", "2026-01-01T00:00:00+00:00", input={"path": "m.csv"},
...                    space={}, settings={}, estimate={"x1d_mpa": 0.04, "x1h_mpa": 5e-4},
...                    at_bound={}, best_run={}, spread={}, E={}, iterations={}, noise=None,
...                    intervals=None, geometry={}, fit={}, runs=[], warnings=[])
>>> r.x1d_mpa, r["estimate"]["x1h_mpa"], list(r.to_json())[:3]
(0.04, 0.0005, ['skinsuction_version', 'created_utc', 'input'])
>>> r.get("intervals", "none"), "fit" in r, "kind" in r
(None, True, False)
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import ClassVar

from skinsuction.results import write_json

__all__ = ["Identification", "TimeIdentification", "write_identification"]


class _JsonView:
    """``to_json()`` from the dataclass fields, and the mapping view of it."""

    #: written first in the JSON when set (a constant of the type, not a field)
    KIND: ClassVar[str | None] = None

    def to_json(self) -> dict:
        """The content of ``identification.json``: the fields in their order.

        Returns
        -------
        dict
            ``{field name: value}`` (``kind`` first for a kind of result that has
            one); the values are the fields themselves, not copies, and may hold
            NaN (the writer makes them null).
        """
        head = {} if self.KIND is None else {"kind": self.KIND}
        return {**head, **{f.name: getattr(self, f.name) for f in fields(self)
                           if f.metadata.get("json", True)}}

    # the mapping view of the JSON, for callers written for the dict result
    def __getitem__(self, key: str):
        return self.to_json()[key]

    def get(self, key: str, default=None):
        """``to_json().get(key, default)`` (the mapping view of the JSON)."""
        return self.to_json().get(key, default)

    def keys(self):
        """``to_json().keys()`` (the mapping view of the JSON)."""
        return self.to_json().keys()

    def __contains__(self, key) -> bool:
        return key in self.to_json()


@dataclass(eq=False)
class Identification(_JsonView):
    """X1d and X1h of a pressure ramp (:func:`~.measured_fit.identify_data`).

    Attributes
    ----------
    skinsuction_version, created_utc : str
        The package's version and the time of the result (ISO 8601, UTC, seconds).
    input : dict
        ``path``, ``sha256`` (None until :func:`~.measured_fit.identify_measured`
        fills it in), ``metadata`` (the file's header) and ``curves`` (per probe: the
        replicate fitted, its first line, its points).
    space : dict
        The space read (its ``info``), ``bottom``, ``kind`` (``scale_free`` or
        ``grid``), the search bounds and the grid shapes.
    settings : dict
        ``objective``, ``probe_mm``, ``alpha``, ``repeats``, ``seed``,
        ``window_focusing``, ``excluded_pressures_mbar``.
    estimate : dict
        ``x1d_mpa``, ``x1h_mpa`` (the median of the runs, polished), the statistic,
        ``window_focusing_median_mpa`` (before the polish).
    at_bound : dict
        Per parameter (``X1d``, ``X1h``): whether the estimate sits on an edge of
        the space, which, and the configuration key that widens it.
    best_run, spread, E, iterations : dict
        The run of least E; the spread of the runs (sd, interquartile range,
        range); E at the estimate and over the runs (eq. 7); the iterations.
    noise : dict or None
        The noise sd of one deflection and how it was found.
    intervals : dict or None
        Profile-likelihood intervals of X1d and X1h (None with a warning when the
        noise is unknown).
    geometry : dict
        The layers, given or assumed, notes, and the effect of a thickness sd.
    fit : dict
        Per probe: the measured and fitted curves and the residuals (µm).
    runs : list of dict
        Each window focusing run: X1d, X1h, E, iterations.
    warnings : list of str
        Everything the user should read, in the order found.
    skin : dict or None
        The fitted skin (:meth:`skinsuction.model.Skin.to_dict`): the estimate on
        the layers and bottom the fit assumed.
    """

    skinsuction_version: str
    created_utc: str
    input: dict
    space: dict
    settings: dict
    estimate: dict
    at_bound: dict
    best_run: dict
    spread: dict
    E: dict
    iterations: dict
    noise: dict | None
    intervals: dict | None
    geometry: dict
    fit: dict
    runs: list
    warnings: list
    skin: dict | None = None

    @property
    def x1d_mpa(self) -> float:
        """The dermis modulus X1d (MPa): ``estimate["x1d_mpa"]``."""
        return self.estimate["x1d_mpa"]

    @property
    def x1h_mpa(self) -> float:
        """The hypodermis modulus X1h (MPa): ``estimate["x1h_mpa"]``."""
        return self.estimate["x1h_mpa"]

    def figure(self):
        """The measured and fitted curves and their residuals.

        Returns
        -------
        matplotlib.figure.Figure
            :func:`skinsuction.figures.fit.plot_fit` of :meth:`to_json`.
        """
        from skinsuction.figures.fit import plot_fit

        return plot_fit(self.to_json())


@dataclass(eq=False)
class TimeIdentification(_JsonView):
    """X1d, X1h and a Prony spectrum of time curves (:func:`~.time_curves.identify_time_data`).

    The JSON starts with ``"kind": "time curves"``.

    Attributes
    ----------
    skinsuction_version, created_utc : str
        The package's version and the time of the result (ISO 8601, UTC, seconds).
    model : dict
        The model fitted, its convention, the number of Prony terms.
    X1d, X1h : float
        The long-time (equilibrium) moduli (MPa).
    g, tau_s : list of float
        The Prony terms' fractions and time constants (s).
    X1d_instantaneous, X1h_instantaneous : float
        ``X1 (1 + sum g)`` (MPa).
    intervals : dict
        Laplace intervals of every parameter, ``level``, ``method``,
        ``misfit_scale``, ``notes``.
    at_bound : dict
        Per parameter: whether it sits on an edge of the space or the spectrum's bounds.
    r_parameters : dict
        ``mode1`` (R parameters per cycle) and ``mode2`` (ramp parameters) records.
    fit_quality : dict
        chi^2 of the fit, per curve and per phase.
    noise, likelihood : dict
        The noise sd per curve and its source; the sd of a point and the pressures.
    space, geometry, settings, input : dict
        The space read and its reach; the layers; the settings; the file read
        (``sha256`` None until :func:`~.time_curves.identify_time_file` fills it in).
    runs : dict
        The window focusing runs of the fit: their iterations, convergence, chi^2,
        how many were polished, the settings.
    fit : dict
        Per curve: time, pressure, measured and fitted deflections, residuals, phases.
    provenance : dict
        Versions, platform, git state and the settings
        (:func:`skinsuction.provenance.collect`).
    warnings : list of str
        Everything the user should read, in the order found.
    skin : dict or None
        The fitted skin (:meth:`skinsuction.model.Skin.to_dict`): the long-time
        moduli and the spectrum (on both layers) on the layers the fit assumed.
    fitted : FittedTimeModel or None
        The fit itself, with the data it was fitted to (not in the JSON): a
        diagnosis of the same curves takes it as its creep model
        (:func:`skinsuction.diagnose.diagnose_time_data`, ``creep``) instead of
        fitting and FE-correcting it again.
    """

    KIND: ClassVar[str] = "time curves"

    skinsuction_version: str
    created_utc: str
    model: dict
    X1d: float
    X1h: float
    g: list
    tau_s: list
    X1d_instantaneous: float
    X1h_instantaneous: float
    intervals: dict
    at_bound: dict
    r_parameters: dict
    fit_quality: dict
    noise: dict
    likelihood: dict
    space: dict
    geometry: dict
    settings: dict
    input: dict
    runs: dict
    fit: dict
    provenance: dict
    warnings: list
    skin: dict | None = None
    fitted: object = field(default=None, repr=False, metadata={"json": False})

    @property
    def kind(self) -> str:
        """``"time curves"``, the JSON's first entry."""
        return self.KIND

    def figure(self):
        """The measured and fitted time curves and their residuals.

        Returns
        -------
        matplotlib.figure.Figure
            :func:`skinsuction.figures.time_fit.plot_time_fit` of :meth:`to_json`.
        """
        from skinsuction.figures.time_fit import plot_time_fit

        return plot_time_fit(self.to_json())


def write_identification(result: Identification | TimeIdentification, out_dir) -> dict:
    """Write ``identification.json`` and ``fit.png`` / ``fit.pdf`` into ``out_dir`` (atomically).

    The one writer of ``skinsuction identify``'s results, a pressure ramp's or
    time curves': the JSON is ``result.to_json()`` (strict:
    :func:`skinsuction.results.write_json`, indented by 2, ASCII), the figure
    ``result.figure()`` (:func:`skinsuction.figures.save_figure`).

    Parameters
    ----------
    result : Identification or TimeIdentification
        Of :func:`skinsuction.identify.measured_fit.identify_data` or
        :func:`skinsuction.identify.time_curves.identify_time_data`.
    out_dir : path-like
        The folder (created if missing).

    Returns
    -------
    dict
        ``{"json": path, "png": path, "pdf": path}``.
    """
    import matplotlib.pyplot as plt

    from skinsuction.figures import save_figure

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = {"json": out / "identification.json", "png": out / "fit.png", "pdf": out / "fit.pdf"}
    write_json(paths["json"], result.to_json(), indent=2, ensure_ascii=True)
    fig = result.figure()
    save_figure(fig, paths["png"], paths["pdf"])
    plt.close(fig)
    return paths
