"""Timing of the identification and the optimiser comparison (paper section 3.3.1).

Window focusing against scipy's ``least_squares`` from random starts and
``differential_evolution`` on the same objectives, and least squares with the
FE model in the loop (:func:`fe_in_the_loop`), once.
"""

from __future__ import annotations

import logging
import math
import time

import numpy as np
import pandas as pd

log = logging.getLogger(__name__)

from skinsuction.evaluation import differential_evolution_fit, least_squares_from_random_starts

from ._runs import _success
from ._setup import PAPER_TIMING, StudySetup, build_objective, case_seed, load_spaces, target_of

def timing_study(setup: StudySetup, *, repeats=100, seed=0, alpha=0.5, sources=None,
                 objectives=("single_6mm", "single_2mm", "weighted", "ratio")):
    """Iterations and time per identification (median over ``repeats``).

    Each identification is timed on its own: ``seconds`` is the window
    focusing loop (wall), ``cpu_seconds`` its process CPU time; the one-off
    ``setup_seconds`` builds the objective (interpolation of the space to the
    measured pressures).  Returns ``(runs, table)``; the table puts the paper's
    numbers (section 3.3.1) next to ours.
    """
    from skinsuction.identify import window_focusing

    frames = []
    for source in sources or setup.sources:
        for kind in objectives:
            t0 = time.perf_counter()
            obj = build_objective(setup, kind, source, alpha)
            setup_s = time.perf_counter() - t0
            window_focusing(obj, seed=0, **setup.window_focusing)  # warm-up (caches, buffers)
            seeds = case_seed(seed, "timing", source, kind).spawn(repeats)
            rows = []
            for k, s in enumerate(seeds):
                c0 = time.process_time()
                r = window_focusing(obj, seed=s, **setup.window_focusing)
                rows.append({"repeat": k, "x1d": r.x1d, "x1h": r.x1h, "E": r.E,
                             "E_unit": r.E_unit, "iterations": r.iterations,
                             "n_evaluations": r.n_evaluations, "seconds": r.seconds,
                             "cpu_seconds": time.process_time() - c0,
                             "converged": r.converged})
            f = pd.DataFrame(rows)
            f.insert(0, "objective", kind)
            f.insert(0, "source", source)
            f["setup_seconds"] = setup_s
            frames.append(f)
    runs = pd.concat(frames, ignore_index=True)
    rows = []
    for (source, kind), g in runs.groupby(["source", "objective"], sort=False):
        paper_it, paper_s = PAPER_TIMING.get(kind, (math.nan, math.nan))
        rows.append({
            "source": source,
            "objective": kind,
            "alpha": alpha if kind == "weighted" else math.nan,
            "runs": len(g),
            "iterations_median": float(g["iterations"].median()),
            "iterations_max": int(g["iterations"].max()),
            "seconds_median": float(g["seconds"].median()),
            "ms_median": 1e3 * float(g["seconds"].median()),
            "cpu_ms_median": 1e3 * float(g["cpu_seconds"].median()),
            "evaluations_median": float(g["n_evaluations"].median()),
            "setup_ms": 1e3 * float(g["setup_seconds"].iloc[0]),
            "converged_fraction": float(g["converged"].mean()),
            "paper_iterations": paper_it,
            "paper_seconds": paper_s,
        })
    return runs, pd.DataFrame(rows)


def reference_minimum(objective, points: int = 201):
    """The global minimiser of ``objective`` inside its bounds, found carefully.

    A dense log-spaced grid (``points`` per axis) locates the basins; the 5 best
    grid points are polished by bounded least squares; the lowest end point
    wins.  Returns ``(x (2,), cost)``.
    """
    from scipy import optimize

    lo, hi = np.asarray(objective.lower, float), np.asarray(objective.upper, float)
    axes = [np.geomspace(lo[i], hi[i], points) for i in range(2)]
    for a, l_, h_ in zip(axes, lo, hi):
        a[0], a[-1] = l_, h_
    xd, xh = np.meshgrid(*axes, indexing="ij")
    cand = np.column_stack([xd.ravel(), xh.ravel()])
    j = np.asarray(objective(cand), dtype=float)
    best_x, best_j = None, np.inf
    for k in np.argsort(j)[:5]:
        if not np.isfinite(j[k]):
            break

        def res(x):
            r = objective.residuals(np.asarray(x, float).reshape(1, 2))[0]
            return np.where(np.isfinite(r), r, 1e3)

        sol = optimize.least_squares(res, cand[k], bounds=(lo, hi), x_scale=hi - lo,
                                     method="trf", xtol=1e-15, ftol=1e-15, gtol=1e-15)
        jj = float(objective(sol.x.reshape(1, 2))[0])
        for x, c in ((sol.x, jj), (cand[k], j[k])):
            if c < best_j:
                best_x, best_j = np.array(x, dtype=float), float(c)
    return best_x, best_j


def optimiser_comparison(setup: StudySetup, *, objectives=("single_6mm",), sources=None,
                         runs=100, least_squares_starts=10, de_runs=20, seed=0,
                         alpha=0.5, success_tolerance=0.01, fe_loop=None):
    """Window focusing against scipy optimisers on the same objective and curve.

    Methods (each run with its own seed):

    * ``window_focusing``: the paper's algorithm (N, Nb, C of the setup), ``runs`` runs;
    * ``least_squares_1_start``: ``scipy.optimize.least_squares`` (trf) from one
      random start, ``runs`` runs -- how much a Gauss-Newton-type method depends
      on its start (paper, section 2.3);
    * ``least_squares_{k}_starts``: the best of ``least_squares_starts`` random
      starts, ``runs`` runs;
    * ``differential_evolution``: scipy's, ``de_runs`` runs;
    * ``fe_in_the_loop`` (optional, from :func:`fe_in_the_loop`): least squares
      with the FE model instead of the space, once.

    A run succeeds against the truth if both moduli are within
    ``success_tolerance`` of it, and against the minimum if both are within
    ``success_tolerance`` of the objective's global minimiser
    (:func:`reference_minimum`), which differs from the truth when the curve
    is not in the interpolated space (source ``fe``).

    Returns ``(runs_frame, table)``.
    """
    from skinsuction.identify import window_focusing

    rows = []
    ref_rows = {}
    for source in sources or setup.sources:
        for kind in objectives:
            obj = build_objective(setup, kind, source, alpha)
            x_ref, j_ref = reference_minimum(obj)
            ref_rows[(source, kind)] = (x_ref, j_ref, float(obj.error(j_ref)))
            methods = {
                "window_focusing": (runs, lambda s: window_focusing(
                    obj, seed=s, **setup.window_focusing)),
                "least_squares_1_start": (runs, lambda s: least_squares_from_random_starts(
                    obj, seed=s, n_starts=1)),
                f"least_squares_{least_squares_starts}_starts": (
                    runs, lambda s: least_squares_from_random_starts(
                        obj, seed=s, n_starts=least_squares_starts)),
                "differential_evolution": (de_runs, lambda s: differential_evolution_fit(
                    obj, seed=s)),
            }
            for method, (n, fit) in methods.items():
                for k, s in enumerate(case_seed(seed, "compare", source, kind, method).spawn(n)):
                    r = fit(s)
                    rows.append({"source": source, "objective": kind, "method": method,
                                 "run": k, "x1d": float(r.estimate[0]),
                                 "x1h": float(r.estimate[1]), "E": float(r.E),
                                 "n_evaluations": int(r.n_evaluations),
                                 "seconds": float(r.seconds)})
                log.info("%s %s %s: %d runs", source, kind, method, n)
    runs_df = pd.DataFrame(rows)
    table = []
    for (source, kind, method), g in runs_df.groupby(["source", "objective", "method"], sort=False):
        x_ref, j_ref, e_ref = ref_rows[(source, kind)]
        table.append({
            "source": source,
            "objective": kind,
            "method": method,
            "runs": len(g),
            "success_truth": float(np.mean(_success(g["x1d"], g["x1h"], setup.target,
                                                    success_tolerance))),
            "success_minimum": float(np.mean(_success(g["x1d"], g["x1h"], x_ref,
                                                      success_tolerance))),
            "evaluations_median": float(g["n_evaluations"].median()),
            "fe_solves": 0,
            "ms_median": 1e3 * float(g["seconds"].median()),
            "x1d_median": float(g["x1d"].median()),
            "x1h_median": float(g["x1h"].median()),
            "E_median": float(g["E"].median()),
            "x1d_minimum": float(x_ref[0]),
            "x1h_minimum": float(x_ref[1]),
            "E_minimum": e_ref,
        })
    if fe_loop is not None:
        table.append({
            "source": "fe (own mesh)",
            "objective": f"single_{fe_loop['probe_mm']:g}mm",
            "method": "fe_in_the_loop",
            "runs": 1,
            "success_truth": float(fe_loop["success"]),
            "success_minimum": math.nan,
            "evaluations_median": float(fe_loop["fe_solves"]),
            "fe_solves": int(fe_loop["fe_solves"]),
            "ms_median": 1e3 * float(fe_loop["seconds"]),
            "x1d_median": fe_loop["estimate"][0],
            "x1h_median": fe_loop["estimate"][1],
            "E_median": fe_loop["E_um"],
            "x1d_minimum": setup.target[0],
            "x1h_minimum": setup.target[1],
            "E_minimum": 0.0,
        })
    return runs_df, pd.DataFrame(table)


class _Budget(Exception):
    pass


def fe_in_the_loop(*, target, bounds, probe_mm=6.0, bottom="fixed", mesh=None,
                   pressures_mbar=None, max_fe_solves=60, seed=0, start=None,
                   diff_step=1e-3, success_tolerance=0.01, simulate=None) -> dict:
    """The standard inverse approach: least squares with the FE model in the loop.

    The curve to identify is a direct FE run at ``target`` with the same mesh
    and pressures as the loop (so the truth is an exact minimum and the run
    measures the optimiser, not the mesh).  ``scipy.optimize.least_squares``
    (trf, bounds, variables scaled by the window, forward differences with a
    relative step ``diff_step``) starts from a seeded random point in ``bounds``
    (or ``start``) and may call the FE model at most ``max_fe_solves`` times
    (Jacobian solves included); at the cap it stops with the best point so far.

    Returns a JSON-able dict: start, estimate, relative errors, success,
    fe_solves, seconds (the loop, without the target solve), seconds per solve,
    E (eq. 7, µm), the settings and the path of the iterates.
    """
    from scipy import optimize

    if simulate is None:
        from skinsuction.model import simulate
    from skinsuction.model import Skin
    mesh = dict(mesh or {})
    p = np.asarray(pressures_mbar if pressures_mbar is not None else np.arange(0, 101, 10.0),
                   dtype=float)
    lo, hi = (np.asarray(b, dtype=float) for b in bounds)
    target = np.asarray(target, dtype=float)

    t0 = time.perf_counter()
    ref = simulate(Skin.two_layer(target[0], target[1], bottom=bottom), probe=probe_mm, pressures_mbar=p, mesh=mesh)
    target_seconds = time.perf_counter() - t0
    ok = np.isfinite(np.asarray(ref.deflection_mm, dtype=float))
    measured = np.asarray(ref.deflection_mm, dtype=float)

    history, cache = [], {}
    best = {"x": None, "cost": np.inf}

    def residuals(x):
        key = tuple(np.round(x, 15))
        if key in cache:
            return cache[key]
        if len(history) >= max_fe_solves:
            raise _Budget
        s0 = time.perf_counter()
        c = simulate(Skin.two_layer(x[0], x[1], bottom=bottom), probe=probe_mm, pressures_mbar=p, mesh=mesh)
        m = np.asarray(c.deflection_mm, dtype=float)
        r = np.where(np.isfinite(m[ok]), measured[ok] - m[ok], 1.0)  # 1 mm: not converged
        cost = 0.5 * float(r @ r)
        history.append({"x1d": float(x[0]), "x1h": float(x[1]), "cost": cost,
                        "converged": bool(c.converged), "seconds": time.perf_counter() - s0})
        if cost < best["cost"]:
            best.update(x=np.array(x, dtype=float), cost=cost)
        cache[key] = r
        return r

    x0 = (lo + (hi - lo) * np.random.default_rng(seed).random(2)) if start is None \
        else np.asarray(start, dtype=float)
    t0 = time.perf_counter()
    status, message = None, ""
    try:
        sol = optimize.least_squares(residuals, x0, bounds=(lo, hi), x_scale=hi - lo,
                                     method="trf", diff_step=diff_step)
        status, message = int(sol.status), str(sol.message)
        if 0.5 * float(sol.fun @ sol.fun) <= best["cost"]:
            best.update(x=np.array(sol.x, dtype=float), cost=0.5 * float(sol.fun @ sol.fun))
    except _Budget:
        status, message = -100, f"stopped at the cap of {max_fe_solves} FE solves"
    seconds = time.perf_counter() - t0
    x = best["x"]
    rel = x / target - 1
    n_used = int(ok.sum())
    return {
        "method": "scipy.optimize.least_squares (trf, 2-point Jacobian) with the FE model",
        "probe_mm": float(probe_mm),
        "bottom": bottom,
        "mesh": mesh,
        "pressures_mbar": p.tolist(),
        "target": target.tolist(),
        "target_converged": bool(ref.converged),
        "target_seconds": target_seconds,
        "bounds": [lo.tolist(), hi.tolist()],
        "start": np.asarray(x0).tolist(),
        "seed": seed,
        "diff_step": diff_step,
        "max_fe_solves": int(max_fe_solves),
        "estimate": x.tolist(),
        "relative_error": rel.tolist(),
        "success": bool(np.all(np.abs(rel) <= success_tolerance)),
        "success_tolerance": success_tolerance,
        "cost_mm2": best["cost"],
        "E_um": 1e3 * math.sqrt(2 * best["cost"]) / n_used,
        "fe_solves": len(history),
        "seconds": seconds,
        "seconds_per_solve": seconds / max(len(history), 1),
        "status": status,
        "message": message,
        "history": history,
    }


def write_fe_in_the_loop(space_path, out_json, settings: dict, loop: dict,
                         pressures_mbar, simulate=None) -> dict:
    """Run :func:`fe_in_the_loop` within the bounds of the space; write the JSON record."""
    import json

    from skinsuction._files import atomic_output

    probe = float(loop.get("probe_mm", 6.0))
    bottom = settings.get("bottom", "fixed")
    s = load_spaces(space_path, (probe,), bottom)[probe]
    result = fe_in_the_loop(
        target=target_of(settings), bounds=(s.lower, s.upper), probe_mm=probe, bottom=bottom,
        mesh=loop.get("mesh"), pressures_mbar=pressures_mbar,
        max_fe_solves=int(loop.get("max_fe_solves", 80)), seed=int(loop.get("seed", 0)),
        success_tolerance=float(settings.get("success_tolerance", 0.01)), simulate=simulate,
    )
    log.info("FE in the loop: %d FE solves, %.1f s, estimate %s (relative error %s), %s",
             result["fe_solves"], result["seconds"], result["estimate"],
             result["relative_error"], result["message"])
    with atomic_output(out_json) as tmp:
        tmp.write_text(json.dumps(result, indent=2) + "\n", encoding="utf-8")
    return result
