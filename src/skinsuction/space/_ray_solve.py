"""FE runs of the scale-free space: one ray per (probe, X1h/X1d, cause value), in bundles.

A ray is one FE curve at ``X1d = x1d_ref`` loaded to ``q = load_max`` (its
first step refined near 0); the workflow's jobs write a bundle
of rays per (model, probe, ratio) (:func:`compute_bundle`), and
:func:`build_ray_spaces` does the same without the workflow (notebooks, tests).
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pandas as pd

from skinsuction._progress import Progress

from ._causes import BASELINE
from ._ray_space import assemble_ray_space
from ._rays import EXTRA_KEYWORDS, RaySpec, parse_ray_id, ray_bundles
from ._solve import solve_with_fallbacks
from ._storage import AXES, _write_parquet, curve_frame

log = logging.getLogger(__name__)

__all__ = ["compute_ray", "compute_bundle", "build_ray_spaces"]


# ---------------------------------------------------------------------- FE rays
def compute_ray(rid: str, pressures_mbar, mesh: dict | None = None, fallback=None,
                fallback_below_mbar: float | None = None):
    """Run the FE model (and its fallbacks) for the ray ``rid``.

    One solve runs every pressure, the onset loads near 0 included (see
    :attr:`RaySpec.load_refine`): the solver's increments grow to the largest
    spacing of the pressures, so the onset's small first steps cost a few
    increments, not a solve of their own.

    Parameters
    ----------
    rid : str
        The ray id (:func:`skinsuction.space.ray_id`): the skin, probe and bottom.
    pressures_mbar : sequence of float
        The pressures of the FE run (``RaySpec.pressures_mbar``).
    mesh : dict, optional
        Mesh and solver settings.
    fallback : dict or list of dict, optional
        Fallback meshes (:func:`skinsuction.space.solve_with_fallbacks`); a
        fallback's curve is spliced on where the first solve stopped.
    fallback_below_mbar : float, optional
        The fallbacks run only for a solve that stopped below this pressure
        (:attr:`RaySpec.fallback_below_mbar`), but for every ray of a stiffening
        dermis (X2d > 0): those stop in the tail for the default element, not
        for want of an equilibrium.

    Returns
    -------
    curve : skinsuction.model.Curve
    frame : pandas.DataFrame
        The ray's rows (one per pressure) with ``ray_id`` and the extra keywords.
    info : dict
        The solver's record: converged, last pressure, reason, iterations,
        seconds, the fallback kept.
    """
    params = parse_ray_id(rid)
    extras = {k: params[k] for k in EXTRA_KEYWORDS if params[k] != EXTRA_KEYWORDS[k]}
    axes = {k: params[k] for k in AXES}
    pressures = np.asarray(pressures_mbar, dtype=float)
    if params["x2d"] > 0:
        # a stiffening dermis that stops in the tail stops for the default element (a
        # soft hypodermis under 4-8 mm): the fallback carries it to 500 mbar on 0.007
        fallback_below_mbar = None
    curve, kept, first_reason = solve_with_fallbacks({**axes, **extras}, pressures, mesh,
                                                     fallback, label=f"ray {rid}", splice=True,
                                                     fallback_below_mbar=fallback_below_mbar)
    frame = curve_frame(curve, axes)
    for k in EXTRA_KEYWORDS:
        frame[k] = float(params[k])
    frame = frame.drop(columns=["point_id"], errors="ignore")
    frame["ray_id"] = rid
    info = {"converged": bool(curve.converged),
            "last_converged_mbar": float(curve.last_converged_mbar),
            "reason": str(curve.reason or ""), "newton_iterations": int(curve.newton_iterations or 0),
            "seconds": float(curve.seconds or 0.0), "mesh_fallback": int(kept),
            "first_solve_reason": first_reason, "curve_info": dict(curve.info or {})}
    return curve, frame, info


def compute_bundle(ray_ids, path, pressures_mbar, mesh: dict | None = None, fallback=None,
                   metadata=None, fallback_below_mbar: float | None = None) -> dict:
    """Run the rays of one bundle and write them to one file (atomic Parquet).

    The adapter of the workflow's ``simulate_ray_bundle`` rule.  A ray that stops
    early is written as it is (NaN beyond its last converged pressure), with its
    reason; an exception of the model becomes a failed ray, never a missing one.

    Parameters
    ----------
    ray_ids : iterable of str
        The rays of the bundle.
    path : path-like
        The bundle file.
    pressures_mbar : sequence of float
        The pressures of the FE runs.
    mesh : dict, optional
        Mesh and solver settings.
    fallback : dict or list of dict, optional
        Fallback meshes.
    metadata : dict, optional
        Extra provenance for the file.
    fallback_below_mbar : float, optional
        See :func:`compute_ray`.

    Returns
    -------
    dict
        ``{ray_id: info}``: each ray's solver record (:func:`compute_ray`).
    """
    from skinsuction.provenance import collect

    frames, infos = [], {}
    for rid in ray_ids:
        _, frame, info = compute_ray(rid, pressures_mbar, mesh, fallback, fallback_below_mbar)
        frames.append(frame)
        infos[rid] = info
    meta = {"rays": infos, "mesh": mesh, "mesh_fallback": fallback,
            "fallback_below_mbar": fallback_below_mbar, "provenance": collect(),
            **(metadata or {})}
    _write_parquet(pd.concat(frames, ignore_index=True), path, meta)
    return infos


def build_ray_spaces(spec: RaySpec, causes: dict, out_dir=None, workers: int = 1,
                     config=None, progress=None) -> dict:
    """Run every bundle in this process (or a pool) and return ``{name: RaySpace}``.

    For tests, notebooks and benchmarks; the workflow runs one job per bundle.
    With ``out_dir`` the bundle and space files are written there
    (``out_dir/rays/<bundle>.parquet``, ``out_dir/<name>.parquet``); bundle files
    already present are reused.

    Parameters
    ----------
    spec : RaySpec
    causes : dict
        ``{name: Cause}``: the causes' spaces besides the neo-Hookean one.
    out_dir : path-like, optional
        Where the files are written (default: a temporary folder, removed).
    workers : int
        Processes that run the bundles.
    config : dict, optional
        The configuration, recorded in each space's provenance.
    progress : text stream, optional
        Where progress goes (default stderr): a bar on a terminal, a line every
        10 s otherwise.

    Returns
    -------
    dict
        ``{name: RaySpace}``, ``neo_hookean`` included.
    """
    import tempfile

    tmp = None
    if out_dir is None:
        tmp = tempfile.TemporaryDirectory(prefix="skinsuction-rays-")
        out_dir = tmp.name
    out = Path(out_dir)
    (out / "rays").mkdir(parents=True, exist_ok=True)
    bundles = ray_bundles(spec, causes)
    jobs = [(ids, str(out / "rays" / f"{bid}.parquet"), spec.pressures_mbar, spec.mesh,
             list(spec.fallback), spec.fallback_below_mbar)
            for bid, ids in bundles.items() if not (out / "rays" / f"{bid}.parquet").exists()]
    # minutes to hours: a bar on a terminal, a line every 10 s in a log
    bar = Progress(len(jobs), "rays", "bundles", stream=progress, quiet_below=2.0)
    if workers > 1 and len(jobs) > 1:
        from concurrent.futures import ProcessPoolExecutor

        with ProcessPoolExecutor(workers) as pool:
            for path in pool.map(_compute_bundle_job, jobs):
                bar.step(note=Path(path).stem)
    else:
        for job in jobs:
            bar.step(note=Path(_compute_bundle_job(job)).stem)
    bar.close()
    paths = [out / "rays" / f"{bid}.parquet" for bid in bundles]
    spaces = {}
    for name, cause in {BASELINE: None, **causes}.items():
        spaces[name] = assemble_ray_space(paths, out / f"{name}.parquet", spec, cause, config)
    if tmp is not None:
        tmp.cleanup()
    return spaces


def _compute_bundle_job(job):
    ids, path, pressures, mesh, fallback, below = job
    compute_bundle(ids, path, pressures, mesh, fallback, fallback_below_mbar=below)
    return path
