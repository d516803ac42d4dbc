"""What one design will tell of one skin: computed from the spaces, no FE run.

For a skin and a :class:`~skinsuction.design.Design`, the model's curves at the
design's probes and pressures are read off the spaces at the truth (noise-free).
On them, with the design's sd per point (noise, the 0.01 mm rounding, the spaces'
own error):

* the **profile-likelihood intervals** of X1d, X1h (and of a given thickness's
  offset) around the truth (:func:`skinsuction.diagnose.fit_intervals`): on
  noise-free data they are the intervals a typical noisy measurement gets (the
  chi^2 surface is the expected one); an end at the space's edge is *open*;
* for each cause asked about, the skin with that cause added: whether the best
  neo-Hookean fit misses its curve by the decision's BIC (*detectable*), the
  interval of the cause's parameter, and, against every other cause, the chi^2
  gap of that cause's best fit, whose attribution ceiling Phi(sqrt(g)/2) bounds
  the rate any diagnosis can name the true cause at
  (:func:`skinsuction.evaluation.attribution_ceiling`).
"""

from __future__ import annotations

import math

import numpy as np

from skinsuction.space import BASELINE

from ._box import CAUSE_COLUMNS, Design, relative_halfwidth

__all__ = ["predict_skin"]


#: Loaded points per probe the predictions evaluate: a ramp's noise-free chi^2 is a
#: sum over a smooth curve, so every k-th point at sd sigma/sqrt(k) gives about the same
#: surface (a Riemann sum) at a fraction of the interpolations (a 500 mbar ramp has
#: 250 points a probe); tests/test_design.py checks the predictions against fits of
#: every point.
MAX_POINTS = 26


def _fit_data(space, theta, design: Design, sigma_um: float, space_error: bool) -> tuple:
    """The noise-free curves of ``space`` at ``theta`` as the design measures them
    (thinned to :data:`MAX_POINTS` a probe, their sd scaled to keep the information),
    with the spaces' correlated error and the discretisation's, at the truth's X1d, as
    the diagnosis weighs them (``space_error``: its ``Settings.space_error``)."""
    from skinsuction.diagnose import FitData, ModelCurves, with_space_error

    full = design.pressures()
    keep = np.unique(np.round(np.linspace(0, full.size - 1, min(MAX_POINTS, full.size)))
                     .astype(int))
    p = full[keep]
    scale = math.sqrt(p.size / full.size)
    sigma_um = sigma_um * scale  # the same n / sigma^2
    blank = {q: FitData(q, p, np.zeros_like(p), sigma_um) for q in design.probes_mm}
    model = ModelCurves(space, blank)
    at = np.concatenate([theta, np.zeros(model.d - len(theta))])
    curves = model(at[None, :])
    fd = {q: FitData(q, p, np.asarray(curves[q][0], float), sigma_um)
          for q in design.probes_mm}
    if space_error and all(np.isfinite(d.deflection_mm).all() for d in fd.values()):
        fd = with_space_error(fd, 10.0 ** float(theta[0]), point_scale=scale)
    return fd, at


def _intervals(space, fd, theta, level) -> dict:
    from skinsuction.diagnose import fit_intervals

    return fit_intervals(space, fd, theta, level=level).parameters


def _geometry(skin, design: Design):
    from skinsuction.space import Geometry

    given = tuple(k for k in ("t_d", "t_h") if k in design.given)
    return Geometry(float(skin["t_d_mm"]), float(skin["t_h_mm"]), given=given,
                    sd={k: float(design.given[k]) for k in given})


def predict_skin(skin: dict, design: Design, spaces: dict, settings, *, causes=(),
                 on_demand=None, solve_rays: bool = False) -> dict:
    """One skin measured by one design: intervals, detectability, attribution ceilings.

    Parameters
    ----------
    skin : dict
        A row of :meth:`Box.draw` (``x1d_mpa``, ``x1h_ratio``, the layers and each
        cause's column).
    design : Design
    spaces : dict name -> RaySpace
        The scale-free space (:func:`skinsuction.space.read_ray_spaces`).
    settings : skinsuction.diagnose.Settings
        ``delta_bic``, ``model_error_um``, ``level``, ``window_focusing``.
    causes : iterable of str
        The causes to add one at a time (detectability, their parameter's
        interval, the ceiling against every other cause of the space: the
        diagnosis's candidates, whether asked about or not).
    on_demand : skinsuction.space.OnDemandRays, optional
        For layers other than the paper's 1 mm (read off the geometry space).
    solve_rays : bool
        At other layers, solve each cause's rays there (or read its geometry
        space); otherwise its effect is carried over from 1 mm, an approximation
        (the row's ``notes`` say so).

    Returns
    -------
    dict
        ``design``, ``skin``, ``beyond_space`` (the ramp leaves the space: p/X1d
        above its load range, or the rays stop before its top), ``notes``;
        ``<P>_halfwidth`` and ``<P>_bounded`` for
        X1d, X1h; per cause ``<c>_detectable``, ``<c>_nh_chi2``,
        ``<c>_halfwidth``, ``<c>_bounded`` and ``<c>_vs_<r>_gap`` for every rival r.
    """
    from skinsuction.space import spaces_at

    row = {"design": design.name, "skin": int(skin["skin"]), "beyond_space": False,
           "notes": ""}
    spec = spaces[BASELINE].spec
    if design.max_mbar / float(skin["x1d_mpa"]) > spec.load_max:
        row["beyond_space"] = True
        row["notes"] = (f"{design.max_mbar:g} mbar at X1d {float(skin['x1d_mpa']):.3g} MPa is "
                        f"beyond the space's load range (p/X1d <= {spec.load_max:g})")
        return row
    geometry = _geometry(skin, design)
    # every cause of the space is a rival (the diagnosis weighs them all); the asked
    # ones are also added to the skin
    chosen = spaces if causes else {BASELINE: spaces[BASELINE]}
    sp, notes = spaces_at(chosen, design.probes_mm, geometry, on_demand,
                          solve_causes=solve_rays)
    row["notes"] = "; ".join(notes)
    if design.protocol != "ramp":  # mode 1 or 2: the time model's intervals, no causes
        from ._predict_time import predict_time, time_notes

        row.update(predict_time(skin, design, sp[BASELINE], settings))
        row["notes"] = "; ".join([*notes, *time_notes(design), row.get("notes", "")]).strip("; ")
        return row
    sigma = design.sigma_um(settings.model_error_um)
    theta = np.array([math.log10(float(skin["x1d_mpa"])), math.log10(float(skin["x1h_ratio"]))])
    fd, full = _fit_data(sp[BASELINE], theta, design, sigma, settings.space_error)
    stops = [q for q, d in fd.items() if not np.isfinite(d.deflection_mm).all()]
    if stops:  # the rays stop before the ramp's top here (no FE equilibrium)
        row["beyond_space"] = True
        row["notes"] = "; ".join([*notes, (
            f"the neo-Hookean rays of the {'+'.join(f'{q:g}' for q in stops)} mm probe stop "
            f"before {design.max_mbar:g} mbar at this skin (the FE model finds no "
            "equilibrium there)")])
        return row
    iv = _intervals(sp[BASELINE], fd, full, settings.level)
    truth = {"X1d": float(skin["x1d_mpa"]), "X1h": float(skin["x1d_mpa"] * skin["x1h_ratio"])}
    for k, v in truth.items():
        row[f"{k}_halfwidth"], row[f"{k}_bounded"] = relative_halfwidth(k, v, iv.get(k))
    for name in causes:
        if name not in sp:
            row[f"{name}_detectable"] = math.nan  # not a free cause here (its layer is given)
            continue
        try:
            row.update(_cause_row(name, skin, sp, theta, design, sigma, settings))
        except Exception as err:  # e.g. the cause's rays stop before the ramp's top
            row[f"{name}_detectable"] = math.nan
            row[f"{name}_error"] = f"{type(err).__name__}: {' '.join(str(err).split())}"
    return row


def _cause_row(name, skin, sp, theta, design, sigma, settings) -> dict:
    """The skin with cause ``name`` added: detectable? its interval, its rivals' gaps."""
    from skinsuction.diagnose import fit_model, nested_start

    space = sp[name]
    cause = space.cause
    coordinate = float(skin[CAUSE_COLUMNS[name]])  # X2d/X1d for stiffening, as its axis
    u = float(cause.to_axis(np.clip(coordinate, cause.lower, cause.upper)))
    th = np.concatenate([theta, [u]])
    fd, full = _fit_data(space, th, design, sigma, settings.space_error)
    n = design.pressures().size * len(design.probes_mm)  # the BIC's n: points measured
    wf = settings.window_focusing
    base = fit_model(sp[BASELINE], fd, seed=0, repeats=1, window_focusing_options=wf)
    out = {f"{name}_nh_chi2": float(base.chi2),
           f"{name}_detectable": bool(base.chi2 >= -settings.delta_bic + math.log(n))}
    iv = _intervals(space, fd, full, settings.level)
    symbol = cause.symbol
    truth = float(cause.value(coordinate, float(skin["x1d_mpa"])))
    out[f"{name}_halfwidth"], out[f"{name}_bounded"] = relative_halfwidth(
        symbol, truth, iv.get(symbol))
    for rival, rs in sp.items():
        if rival in (BASELINE, name) or rs.cause is None:
            continue
        start = nested_start(base.theta, rs.cause)
        try:
            f = fit_model(rs, fd, seed=0, repeats=1, window_focusing_options=wf,
                          starts=[start])
        except ValueError:  # no curve of the rival's space near: it cannot mimic this one
            out[f"{name}_vs_{rival}_gap"] = math.inf
            continue
        out[f"{name}_vs_{rival}_gap"] = float(f.chi2)  # the truth's own chi^2 is 0
    return out
