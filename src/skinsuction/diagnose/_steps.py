"""The steps of a diagnosis, each a function of the diagnosis under way (:class:`Run`).

:func:`start` puts the data at the fitted points (:func:`prepare_data`) and the
neo-Hookean space at the subject's layers; :func:`fit_baseline` fits the
neo-Hookean model and tests its residuals; :func:`cause_spaces` gives the causes'
spaces (centred on the baseline's fit when their rays are solved on demand);
:func:`fit_candidate` fits one cause and measures its gain.  The seeds of the fits
are drawn from one :class:`numpy.random.SeedSequence` in this order (baseline,
its holdout, then per cause its fit, any refit in a widened window and its
holdout), so a diagnosis is the same on every run.  :func:`skinsuction.diagnose.diagnose`
composes them, then decides (:mod:`._rule`) and writes the report.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from skinsuction.errors import InputError
from skinsuction.identify import IdentificationError
from skinsuction.model import Skin
from skinsuction.results import jsonable
from skinsuction.space import BASELINE, GeometryOutsideSpace, fit_reach_mm, spaces_at

from ._data import prepare_data
from ._fit import fit_bounds, fit_intervals, fit_model, nested_start, with_space_error
from ._settings import Settings
from ._stats import bic, misfit_test
from ._window import fit_in_window, ratio_window

__all__ = ["BeyondSpaceError", "Run", "Baseline", "start", "fit_baseline", "cause_spaces",
           "fit_candidate", "intervals_json", "fit_json", "residual_dict", "fitted_skin"]


class BeyondSpaceError(InputError):
    """No candidate of the simulated space has a curve over the measured pressures."""


@dataclass(eq=False)
class Run:
    """A diagnosis under way: the data at the fitted points, the noise, the spaces, the seeds.

    Attributes
    ----------
    data : MeasuredData
    settings : Settings
    given_spaces : dict
        The ray spaces given (``{name: RaySpace}``).
    geometry : Geometry
        The subject's layers.
    geometry_warnings : list of str
        What the layers assume (none if ``geometry`` was given).
    on_demand : OnDemandRays or None
        Solves the rays of a probe or layers the spaces lack.
    spaces : dict
        The spaces at the subject's layers: the neo-Hookean one, then the causes'
        (as widened by their fits).
    geometry_notes : list of str
        What the spaces at the layers say (rays solved, effects carried over, windows).
    fd : dict
        ``{probe: FitData}``: the fitted points (with the space's error once the
        baseline is fitted, with ``space_error``).
    noise : NoiseEstimate
    data_info : dict
        Per probe: curves, replicates, points fitted.
    probes, skipped : list of float
        The probes fitted, and those the spaces lack.
    sigma : dict
        ``{probe: sd of a fitted point (µm)}``: the noise the misfit tests judge by.
    n_points : int
        Points fitted.
    seeds : iterator of SeedSequence
        The seeds of the fits, drawn in order.
    """

    data: object
    settings: Settings
    given_spaces: dict
    geometry: object
    geometry_warnings: list
    on_demand: object
    spaces: dict
    geometry_notes: list
    fd: dict
    noise: object
    data_info: dict
    probes: list
    skipped: list
    sigma: dict
    n_points: int
    seeds: object

    @property
    def windowed(self) -> bool:
        """Whether the causes' X1h/X1d window is centred on the baseline's fit (rays on
        demand: the baseline's space first, the causes' after it is fitted)."""
        return self.on_demand is not None and self.settings.cause_window_decades is not None

    @property
    def two_probes(self) -> bool:
        """Whether the cross-probe holdout is measured."""
        return len(self.probes) >= 2 and self.settings.holdout

    def holdout(self, space):
        """The cross-probe holdout of a model's ``space`` (None, None without it).

        Its seed is drawn whenever two probes are there, measured or not: the
        holdout is no part of the decision, and leaving it out changes no other fit.
        """
        seed = next(self.seeds) if len(self.probes) >= 2 else None
        return _holdout(space, self.fd, self.settings, seed) if self.two_probes else (None, None)

    def at_layers(self, names, window=None):
        """The spaces ``names`` at the subject's layers, and their notes."""
        try:
            return spaces_at({n: self.given_spaces[n] for n in names}, self.data.probes,
                             self.geometry, self.on_demand, ratio_window=window,
                             reads_up_to_mm=fit_reach_mm(self.data.curves))
        except GeometryOutsideSpace as err:
            raise InputError(f"{self.data.path}: {err}") from None

    def fit(self, space, starts=()):
        """A fit of ``space`` to the fitted points with the next seed."""
        return fit_model(space, self.fd, seed=next(self.seeds), repeats=self.settings.repeats,
                         window_focusing_options=self.settings.window_focusing, starts=starts)


def start(data, spaces: dict, settings: Settings, geometry=None, on_demand=None) -> Run:
    """Step 1: the fitted points, the noise and the neo-Hookean space at the layers.

    Parameters
    ----------
    data : MeasuredData
    spaces : dict
        ``{name: RaySpace}``: ``neo_hookean`` and the candidate causes.
    settings : Settings
    geometry : Geometry, optional
        The layers; by default those of the data (or the paper's 1 mm, stated).
    on_demand : OnDemandRays, optional
        Solves the rays of a probe or layers the spaces lack.

    Returns
    -------
    Run
    """
    from skinsuction.measured import geometry_of

    geometry_warnings = []
    if geometry is None:
        geometry, geometry_warnings = geometry_of(data)
    run = Run(data, settings, spaces, geometry, geometry_warnings, on_demand, {}, [], {}, None,
              {}, [], [], {}, 0, None)
    run.spaces, run.geometry_notes = run.at_layers(
        [BASELINE] if run.windowed else list(spaces))
    base_space = run.spaces[BASELINE]
    probes = [p for p in data.probes if base_space.has_probe(p)]
    run.skipped = [p for p in data.probes if not base_space.has_probe(p)]
    run.fd, run.noise, run.data_info = prepare_data(data, probes, settings)
    run.probes = sorted(run.fd)
    run.seeds = iter(np.random.SeedSequence(settings.seed).spawn(64))
    run.sigma = {p: run.fd[p].sigma_um for p in run.probes}
    run.n_points = sum(d.n for d in run.fd.values())
    return run


# --------------------------------------------------------------------- the baseline
@dataclass(eq=False)
class Baseline:
    """The neo-Hookean fit and what is measured on it.

    Attributes
    ----------
    space : RaySpace
    fit : Fit
    test : MisfitTest
        The smooth-pattern test of its residuals.
    bic : float
    bounds : dict
        Its parameters' edge flags.
    intervals : dict
        Its profile-likelihood intervals as JSON.
    holdout_E_um : float or None
    holdout : dict or None
        The cross-probe holdout, both directions.
    """

    space: object
    fit: object
    test: object
    bic: float
    bounds: dict
    intervals: dict
    holdout_E_um: float | None
    holdout: dict | None


def _beyond_message(space, fd) -> str:
    spec = space.spec
    p_max = max(float(d.pressure_mbar.max()) for d in fd.values())
    return (f"beyond_space: no neo-Hookean curve of the scale-free space covers the "
            f"measurement up to {p_max:g} mbar (X1d >= {spec.x1d_lower(p_max):.3g} MPa is "
            f"searched, and the FE rays stop before the load p/X1d the fit needs: see "
            f"results/tables/scale_free_coverage.csv); widen scale_free_space.load.max, "
            f"scale_free_space.mesh_fallback or scale_free_space.x1d_mpa")


def fit_baseline(run: Run) -> Baseline:
    """Step 2: the neo-Hookean fit, its misfit test, BIC, edges, intervals and holdout.

    With ``space_error`` the space's error along each curve is weighed at the fit's
    X1d (``run.fd`` takes it on) and the fit is polished under that likelihood, as
    every cause is fitted.

    Parameters
    ----------
    run : Run

    Returns
    -------
    Baseline

    Raises
    ------
    BeyondSpaceError
        No neo-Hookean curve of the space covers the measured pressures.
    """
    settings, space = run.settings, run.spaces[BASELINE]
    try:
        fit = run.fit(space)
    except IdentificationError:
        raise BeyondSpaceError(_beyond_message(space, run.fd)) from None
    if settings.space_error:
        # the space's error grows with the load p / X1d: weigh it at the baseline's X1d,
        # then polish the baseline under that likelihood, as every cause is fitted
        run.fd = with_space_error(run.fd, fit.parameters["X1d"])
        searched = fit.wf
        fit = fit_model(space, run.fd, seed=0, repeats=0, starts=[fit.theta],
                        window_focusing_options=settings.window_focusing)
        fit.wf = {**searched, "space_error_polished": fit.wf["polished"]}
    test = misfit_test(residual_dict(fit, run.fd), run.sigma, run.noise.dof, settings.degree,
                       settings.alpha)
    b = bic(fit.chi2, fit.n_params, run.n_points)
    bounds = fit_bounds(space, run.fd, fit.theta)
    ci = (None if settings.intervals == "cause"
          else intervals_json(space, run.fd, fit.theta, run.noise, settings))
    hold, hold_detail = run.holdout(space)
    return Baseline(space, fit, test, b, bounds, ci, hold, hold_detail)


# --------------------------------------------------------------------- the causes
def cause_spaces(run: Run, base: Baseline) -> list:
    """Step 3a: the causes' spaces at the layers that cover every fitted probe.

    With rays on demand their X1h/X1d window is centred on the baseline's fit
    (``run.spaces`` and ``run.geometry_notes`` are those of the new window).

    Parameters
    ----------
    run : Run
    base : Baseline

    Returns
    -------
    list of tuple
        ``[(name, RaySpace)]`` in the order of the spaces given.
    """
    if run.windowed:
        spaces, run.geometry_notes = run.at_layers(
            list(run.given_spaces), ratio_window(base.fit.theta, run.settings.cause_window_decades))
        spaces[BASELINE] = base.space
        run.spaces = spaces
    return [(name, space) for name, space in run.spaces.items()
            if name != BASELINE and all(space.has_probe(p) for p in run.probes)]


def _fit_in_window(run: Run, name: str, space, fit, null_theta):
    """A cause's fit widened until it lies inside its window (rays on demand)."""
    def rebuild(window):
        wider, notes = run.at_layers([BASELINE, name], window)
        return wider[name], [n for n in notes if n.startswith(f"{name}:")]

    def refit(space, previous):
        return run.fit(space, starts=[previous.theta, null_theta])

    space, fit, notes = fit_in_window(space, fit, run.spaces[BASELINE].spec.ratio_nodes,
                                      run.settings.cause_window_decades, rebuild, refit)
    run.spaces[name] = space
    run.geometry_notes += notes
    return space, fit


def fit_candidate(run: Run, name: str, space, base: Baseline) -> tuple:
    """Step 3b: one cause's fit, started from the baseline, and its gain over it.

    Parameters
    ----------
    run : Run
    name : str
        The cause.
    space : RaySpace
        Its space at the layers (:func:`cause_spaces`).
    base : Baseline

    Returns
    -------
    tuple
        ``(candidate, fit)``: the candidate as in ``report["candidates"]`` (its
        ``intervals`` None unless ``settings.intervals == "all"``) and its Fit.
    """
    settings, cause = run.settings, space.cause
    null_theta = nested_start(base.fit.theta, cause)
    f = run.fit(space, starts=[null_theta])
    if run.windowed:
        space, f = _fit_in_window(run, name, space, f, null_theta)
    t = misfit_test(residual_dict(f, run.fd), run.sigma, run.noise.dof, settings.degree,
                    settings.alpha)
    b = bic(f.chi2, f.n_params, run.n_points)
    hold, hold_detail = run.holdout(space)
    bounds = fit_bounds(space, run.fd, f.theta)
    return {
        "intervals": (intervals_json(space, run.fd, f.theta, run.noise, settings)
                      if settings.intervals == "all" else None),
        "cause": name,
        "hypothesis": cause.hypothesis,
        "parameters": f.parameters,
        "E_um": f.E_um,
        "delta_bic": b - base.bic,
        "holdout_E_um": hold,
        "E_ratio": f.E_um / base.fit.E_um if base.fit.E_um > 0 else None,
        "holdout_ratio": ((hold / base.holdout_E_um)
                          if hold is not None and base.holdout_E_um else None),
        "delta_chi2": f.chi2 - base.fit.chi2,
        "bic": b,
        "systematic_misfit": t.significant,
        "misfit_p_value": t.p_value,
        "decisive": bool(b - base.bic <= settings.delta_bic),
        "removes_misfit": not t.significant,
        "extra_parameter": {"symbol": cause.symbol, "unit": cause.unit,
                            "value": f.parameters[cause.symbol],
                            "coordinate": float(cause.from_axis(f.theta[2])),
                            "coordinate_name": cause.coordinate_name,
                            "range": [cause.lower, cause.upper],
                            "at_bound": bounds[cause.symbol]["at_bound"]
                            and not bounds[cause.symbol]["neutral"]},
        "at_bound": bounds,
        "fit": fit_json(f, t),
        "holdout": hold_detail,
        "skin": fitted_skin(run, f, cause),
    }, f


def fitted_skin(run: Run, fit, cause=None) -> dict:
    """The skin a fit describes (:meth:`skinsuction.model.Skin.to_dict`).

    Parameters
    ----------
    run : Run
        Its layers (given or assumed) and the spaces' bottom.
    fit : Fit
        The fit: X1d, X1h, a cause's parameter, thickness offsets.
    cause : Cause or tuple of Cause, optional
        The cause fitted (or a pair's two); its parameter goes on its paths
        (:attr:`Cause.paths`).

    Returns
    -------
    dict
    """
    p = fit.parameters
    bottom = next(iter(run.spaces.values())).spec.bottom
    skin = Skin.two_layer(p["X1d"], p["X1h"], t_d=p.get("t_d", run.geometry.t_d),
                          t_h=p.get("t_h", run.geometry.t_h), bottom=bottom)
    causes = () if cause is None else (cause if isinstance(cause, tuple) else (cause,))
    for c in causes:
        skin = skin.replace({path: p[c.symbol] for path in c.paths})
    return skin.to_dict()


# --------------------------------------------------------------------- measures of a fit
def intervals_json(space, fd, theta, noise, settings: Settings) -> dict:
    """A fit's profile-likelihood intervals as JSON.

    Parameters
    ----------
    space : RaySpace
    fd : dict
        ``{probe: FitData}``.
    theta : ndarray
        The fit's coordinates.
    noise : NoiseEstimate
        Its degrees of freedom widen the intervals.
    settings : Settings
        ``level``.

    Returns
    -------
    dict
        The intervals, or ``{"error": reason}`` if they fail.
    """
    try:
        return fit_intervals(space, fd, theta, noise_dof=noise.dof,
                             level=settings.level).to_dict()
    except ValueError as err:
        return {"error": str(err)}


def residual_dict(fit, data, independent=True) -> dict:
    """A fit's residuals per probe.

    Parameters
    ----------
    fit : Fit
    data : dict
        ``{probe: FitData}``.
    independent : bool
        True: with the space's correlated error taken out (what the misfit test
        judges); False: as measured minus fitted.

    Returns
    -------
    dict
        ``{probe: (pressure mbar, residual µm)}``.
    """
    res = fit.independent_um if independent else fit.residual_um
    return {p: (data[p].pressure_mbar, res[p]) for p in data}


def _finite(a) -> list:
    return jsonable(np.asarray(a, dtype=float))


def fit_json(fit, test=None) -> dict:
    """A fit as in the report: parameters, E, chi², curves, residuals, misfit test.

    Parameters
    ----------
    fit : Fit
    test : MisfitTest, optional
        The smooth-pattern test of its residuals.

    Returns
    -------
    dict
        Non-finite values of the curves are None.
    """
    return {
        "parameters": fit.parameters,
        "E_um": fit.E_um,
        "rms_um": fit.rms_um,
        "chi2": fit.chi2,
        "n_points": fit.n_points,
        "n_params": fit.n_params,
        "fitted_mm": {f"{p:g}": _finite(c) for p, c in fit.fitted_mm.items()},
        "residual_um": {f"{p:g}": _finite(c) for p, c in fit.residual_um.items()},
        "misfit_test": test.to_dict() if test is not None else None,
        "optimiser": fit.wf,
    }


def _holdout(space, data, settings, seed):
    """Fit on one probe alone, predict the other.

    Returns (E of the holdout in µm, detail).  The holdout E is that of the
    smaller probe predicted from a fit of the larger one (6 -> 2 mm): the paper
    (section 3.2, Figure 4) shows that the 6 mm probe identifies both layers and
    the 2 mm probe alone cannot identify X1h, so the other direction fails for
    every model; it is reported in the detail.
    """
    from ._fit import ModelCurves

    probes = sorted(data)
    small, large = probes[0], probes[-1]
    detail, main = {}, None
    for train, test in ((large, small), (small, large)):
        f = fit_model(space, {train: data[train]}, seed=seed, repeats=1,
                      window_focusing_options=settings.window_focusing)
        pred = ModelCurves(space, {test: data[test]})(f.theta[None, :])[test][0]
        e = 1e3 * (data[test].deflection_mm - pred)
        s = float((e ** 2).sum())
        ok = math.isfinite(s)
        d = {"parameters": f.parameters, "E_um": math.sqrt(s) / e.size if ok else None,
             "rms_um": math.sqrt(s / e.size) if ok else None}
        detail[f"fit_{train:g}_predict_{test:g}"] = d
        if main is None:
            main = d["E_um"]
    return main, detail
