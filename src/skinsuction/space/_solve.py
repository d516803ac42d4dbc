"""FE solves that do not give up: the fallback meshes of a grid point or a ray."""

from __future__ import annotations

import logging

import numpy as np

from ._storage import parse_point_id, write_curve, write_curves

log = logging.getLogger(__name__)


def _reached(curve) -> float:
    return float(np.nan_to_num(curve.last_converged_mbar, nan=-1.0))


def _splice(curve, other, pressures):
    """``curve`` where it converged, ``other`` beyond, scaled to meet it there."""
    import dataclasses

    m0 = np.asarray(curve.deflection_mm, dtype=float)
    m1 = np.asarray(other.deflection_mm, dtype=float)
    ok = np.flatnonzero((pressures <= _reached(curve)) & np.isfinite(m0))
    if ok.size < 2 or not np.isfinite(m1[ok[-1]]) or m1[ok[-1]] == 0:
        return other, None
    k = ok[-1]
    factor = float(m0[k] / m1[k])
    merged = m1 * factor
    merged[: k + 1] = m0[: k + 1]
    info = {**(other.info or {}), "spliced_at_mbar": float(pressures[k]),
            "splice_factor": factor}
    return dataclasses.replace(other, deflection_mm=merged, info=info), float(pressures[k])


#: a grid point's keys that describe the paper's two-layer skin (the rest: the probe)
TWO_LAYER_KEYS = ("x1d", "x1h", "x2d", "x2h", "t_d", "t_h", "bottom", "prestretch")


def two_layer_skin(model, params):
    """The skin and probe (mm) of a grid point or ray's flat parameters.

    Parameters
    ----------
    model : module
        The forward model (:mod:`skinsuction.model`, or a workflow test's stand-in).
    params : dict
        ``x1d, x1h`` and optionally ``x2d, x2h, t_d, t_h, bottom, prestretch,
        probe_mm``.

    Returns
    -------
    (Skin, float)
    """
    unknown = set(params) - set(TWO_LAYER_KEYS) - {"probe_mm"}
    if unknown:
        raise getattr(model, "ParameterError", ValueError)(
            f"unknown model parameter(s) {sorted(unknown)}; a grid point has "
            f"{list(TWO_LAYER_KEYS) + ['probe_mm']}")
    skin = model.Skin.two_layer(**{k: v for k, v in params.items() if k in TWO_LAYER_KEYS})
    return skin, params.get("probe_mm", 6.0)


def _solve_once(params: dict, pressures, settings: dict, label: str, budget=None,
                stall_after=None):
    """One solve of the FE model at ``params`` with the mesh ``settings``, logged.

    A :class:`skinsuction.model.ParameterError` is raised naming the label, the
    parameters and the settings; any other exception of the model becomes a
    failed curve (all NaN, ``reason="exception: ..."``)."""
    import time

    from skinsuction import model
    from skinsuction.model import Curve, simulate

    # a stand-in model (workflow tests) may not define it: then nothing is refused
    ParameterError = getattr(model, "ParameterError", ())  # noqa: N806

    log.info("%s: %s, %d pressures, mesh %s", label, params, pressures.size, settings)
    start = time.perf_counter()
    try:
        extra = {} if budget is None else {"iteration_budget": budget}
        if stall_after is not None:
            extra["stall_after"] = stall_after
        skin, probe = two_layer_skin(model, params)
        curve = simulate(skin, probe, pressures_mbar=pressures, mesh=settings, **extra)
    except ParameterError as err:
        # refused parameters or mesh settings are the configuration's error, not a
        # non-converged point: the job fails, loudly, naming them
        raise ParameterError(f"{label}: the model refuses {params} with mesh "
                             f"{settings}: {err}") from None
    except Exception as err:  # the model promises not to raise; record it if it does
        log.exception("the model raised at %s", label)
        curve = Curve(
            pressure_mbar=pressures,
            deflection_mm=np.full(pressures.shape, np.nan),
            converged=False,
            last_converged_mbar=float("nan"),
            reason=f"exception: {type(err).__name__}: {err}",
            seconds=time.perf_counter() - start,
        )
    log.info("%s: converged=%s last=%s mbar reason=%r newton=%s dofs=%s %.1f s", label,
             curve.converged, curve.last_converged_mbar, curve.reason,
             curve.newton_iterations, curve.dofs, curve.seconds)
    return curve


def solve_with_fallbacks(params: dict, pressures_mbar, mesh: dict | None = None, fallback=None,
                         label: str = "model", splice: bool = False,
                         fallback_below_mbar: float | None = None):
    """Solve the FE model, then the fallback meshes in order while it stops early.

    The chain of :func:`compute_point`, for any model keywords (``params`` are
    passed to :func:`skinsuction.model.simulate`, e.g. with ``prestretch``).
    An exception of the model is logged and returned as a failed curve (all
    NaN, ``reason="exception: ..."``), never raised, except
    :class:`skinsuction.model.ParameterError` (parameters or mesh settings the
    model refuses), which is raised: a workflow job fails loudly.

    ``splice=True`` keeps the first solve's curve up to where it converged and
    takes only the rest from the fallback, scaled to meet it there (``info``
    records ``spliced_at_mbar`` and ``splice_factor``): a fallback element locks
    slightly (up to 0.9 % for stiff skin), and a curve that switched element
    over its whole range would differ by that from a run of the same skin at a
    lower load that the default converges.  The scale-free space and its checks
    splice; the paper grid keeps whole fallback curves.

    Parameters
    ----------
    params : dict
        The grid point's or ray's keywords (:func:`two_layer_skin`: ``x1d, x1h``
        and optionally ``x2d, x2h, t_d, t_h, bottom, prestretch, probe_mm``), as
        its id spells them.
    pressures_mbar : sequence of float
        Pressures of the curve, ascending from 0.
    mesh : dict, optional
        Mesh and solver settings of the first solve.
    fallback : dict or list of dict, optional
        Settings that replace those of ``mesh`` for each further solve (see
        :func:`compute_point`).
    label : str
        Names the solve in the log and in errors.
    splice : bool
        Splice a fallback's curve onto the first solve's (above).
    fallback_below_mbar : float, optional
        Run the fallbacks only for a first solve that stopped below this pressure
        (the rays' load tail, :attr:`RaySpec.fallback_below_mbar`: there only
        neo-Hookean skins stop, at stretches of 4-13, and a fallback from 0 would
        double the ray's cost for a few per cent more load).

    Returns
    -------
    (Curve, int, str or None)
        The curve that reaches the highest pressure (its ``seconds`` count every
        solve, its ``info["mesh_fallback"]`` says which fallback, from 1), the
        index of that fallback (0: the first solve) and the first solve's reason
        when a fallback's curve was kept.
    """
    import dataclasses

    pressures = np.asarray(pressures_mbar, dtype=float)

    def solve(settings, budget=None, stall_after=None):
        return _solve_once(params, pressures, settings, label, budget, stall_after)

    curve = solve(dict(mesh or {}))
    first_reason, kept, spent = None, 0, curve.seconds
    fallbacks = [fallback] if isinstance(fallback, dict) else list(fallback or [])
    if fallback_below_mbar is not None and _reached(curve) >= fallback_below_mbar:
        fallbacks = []
    for k, settings in enumerate(fallbacks, start=1):
        if curve.converged:
            break
        settings = dict(settings)
        per_step = settings.pop("iterations_per_step", 20)
        stall_after = settings.pop("stall_after", None)
        other = solve({**dict(mesh or {}), **settings}, per_step * pressures.size, stall_after)
        spent += other.seconds
        if _reached(other) > _reached(curve):
            log.info("%s: kept the curve of fallback %d", label, k)
            first_reason = curve.reason if kept == 0 else first_reason
            if splice:
                other, at = _splice(curve, other, pressures)
                if at is not None:
                    log.info("%s: spliced at %g mbar (factor %.6f)", label, at,
                             other.info["splice_factor"])
            kept, curve = k, other
    if kept:
        curve = dataclasses.replace(curve, info={**(curve.info or {}), "mesh_fallback": kept})
    if spent != curve.seconds:  # every solve's time counts
        curve = dataclasses.replace(curve, seconds=spent)
    return curve, kept, first_reason



def compute_point(
    pid: str, path, pressures_mbar, mesh: dict | None = None, metadata=None, fallback=None
):
    """Run the FE model at the grid point ``pid`` and write its curve file.

    The adapter of the workflow's ``simulate_point`` rule. A solve that does not
    converge is written as it is (``converged=False``); an exception raised by
    the model is logged with its traceback and written as a failed point too
    (``reason="exception: ..."``, all deflections NaN), so that a space never
    silently loses a grid point.

    Parameters
    ----------
    pid : str
        Point id (see :func:`point_id`).
    path : path-like
        Output curve file.
    pressures_mbar : sequence of float
        Pressures of the curve, ascending from 0.
    mesh : dict, optional
        Mesh and solver settings (``config["mesh"]``), passed through.
    metadata : dict, optional
        Extra provenance (e.g. the source hash of the model).
    fallback : dict or list of dict, optional
        Mesh settings (``config["mesh_fallback"]``) that replace those of ``mesh``
        for another solve while the solves so far stopped early, in order, each
        with ``iterations_per_step`` (its Newton budget per pressure, default 20)
        and optionally ``stall_after`` (see :meth:`skinsuction.model.SuctionTest.run`).
        The curve that reaches the highest pressure is kept; ``mesh_fallback`` in
        its rows says whether it is a fallback's, the metadata which one
        (``mesh_fallback_kept``, from 1) and the first solve's reason.

    Returns
    -------
    Curve
    """
    from skinsuction.provenance import collect

    curve, params, own = _solve_point(pid, pressures_mbar, mesh, fallback)
    meta = {"mesh": mesh, "mesh_fallback": fallback, "provenance": collect(), **(metadata or {})}
    write_curve(curve, params, path, {**meta, **own})
    return curve


def _solve_point(pid, pressures_mbar, mesh, fallback):
    """A point's curve, its axes and what its metadata says of its fallbacks."""
    params = parse_point_id(pid)
    curve, kept, first_reason = solve_with_fallbacks(params, pressures_mbar, mesh, fallback,
                                                     label=f"point {pid}")
    own = {}
    if kept:
        own["mesh_fallback_kept"] = kept
    if first_reason is not None:
        own["first_solve_reason"] = first_reason
    return curve, params, own


def compute_points(
    pids, path, pressures_mbar, mesh: dict | None = None, metadata=None, fallback=None
):
    """Run the FE model at several grid points (a row) and write them to one file.

    The adapter of the workflow's ``simulate_row`` rule: :func:`compute_point`
    for each point, in one process, written together (:func:`write_curves`)
    once all are solved; a failed point is written as failed, as there.

    Parameters
    ----------
    pids : sequence of str
        Point ids (see :func:`point_id`).
    path : path-like
        Output file.
    pressures_mbar, mesh, metadata, fallback
        As :func:`compute_point`.

    Returns
    -------
    list of Curve
    """
    from skinsuction.provenance import collect

    solved = [_solve_point(pid, pressures_mbar, mesh, fallback) for pid in pids]
    meta = {"mesh": mesh, "mesh_fallback": fallback, "provenance": collect(), **(metadata or {})}
    write_curves(solved, path, meta)
    return [curve for curve, _, _ in solved]
