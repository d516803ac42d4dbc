"""The diagnosis of measured suction curves: the steps composed, the report assembled.

:func:`diagnose` runs the steps of ``skinsuction diagnose`` on loaded data and the
ray spaces: the data at the fitted points and the neo-Hookean fit
(:mod:`._steps`), each candidate cause's fit, the verdict (the decision rule,
:mod:`._rule`), the report and its summary (:mod:`._summary`).
:func:`diagnose_file` reads the CSV and the spaces first; :func:`write_report`
(:mod:`._report`) writes ``report.json``, ``report.md`` and the figures.
"""

from __future__ import annotations

import datetime as _dt
import time
from dataclasses import asdict

from skinsuction.space import BASELINE

from ._data import MIN_POINTS, prepare_data
from ._rule import BEYOND_SPACE, decide, eligible
from ._settings import Settings
from ._stats import describe_residuals
from ._deferred import fit_candidates
from ._steps import (BeyondSpaceError, fit_baseline, fit_json, fitted_skin, intervals_json,
                     residual_dict, start)
from ._pairs import pair_final, second_effect
from ._summary import summary_text
from ._window import fit_in_window, ratio_window, widened_window

__all__ = ["BeyondSpaceError", "BEYOND_SPACE", "Settings", "diagnose", "diagnose_file",
           "prepare_data",
           # kept importable from here, where they were defined before the split
           "MIN_POINTS", "decide", "summary_text", "fit_in_window", "ratio_window",
           "widened_window"]


def diagnose(data, spaces: dict, settings: Settings | None = None, *, source=None,
             geometry=None, on_demand=None, pairs: dict | None = None) -> dict:
    """Diagnose loaded measured data (:class:`skinsuction.measured.MeasuredData`).

    Parameters
    ----------
    data : MeasuredData
    spaces : dict name -> RaySpace
        ``neo_hookean`` and the candidate causes (see :func:`read_ray_spaces`).
    settings : Settings
    source : dict, optional
        ``{"file": ..., "sha256": ...}`` of the input file for the report.
    geometry : skinsuction.space.Geometry, optional
        The layer thicknesses; by default those of the file's header lines (or a
        study's columns), else the paper's 1 mm, stated as assumptions.  A given
        thickness takes its cause out of the candidates.
    on_demand : skinsuction.space.OnDemandRays, optional
        Solves the neo-Hookean rays of a probe or layers the spaces lack; without
        it such data raise an InputError.
    pairs : dict name -> PairRaySpace, optional
        Spaces of two causes at once (:func:`skinsuction.space.read_pair_spaces`):
        where one cause earns its parameter, a second is tried with them
        (:func:`skinsuction.diagnose._pairs.second_effect`).

    Returns
    -------
    dict
        The report (see the package docstring for its contract).
    """
    t0, c0 = time.perf_counter(), time.process_time()
    settings = settings or Settings()
    run = start(data, spaces, settings, geometry, on_demand)
    base = fit_baseline(run)
    candidates, fits = fit_candidates(run, base)
    best, cause, verdict, ambiguous, beyond, standing = decide(
        base.test.significant, base.bic, base.bounds, candidates, settings)
    # the intervals of the model the verdict stands on (the others' with intervals="all")
    for c in candidates:
        if c["intervals"] is None and c["cause"] == standing:
            c["intervals"] = intervals_json(run.spaces[c["cause"]], run.fd,
                                            fits[c["cause"]].theta, run.noise, settings)
    step = second_effect(run, candidates, fits, pairs or {})
    report = _report(run, base, candidates, source)
    report.update(_verdict(base, candidates, best, cause, verdict, ambiguous, beyond))
    if step["added"] is not None:
        report.update(pair_final(base, step))
        report["ambiguous_with"] = step["ambiguous_with"]
        step["added"].pop("_fit")
    report["second_effect"] = step
    report["steps"] = _steps_json(candidates, report, step)
    report.update({"summary": None, "settings": {**asdict(settings), "n_points": run.n_points},
                   "spaces": _spaces_json(run.spaces), "seconds": None})
    report["summary"] = summary_text(report)
    report["seconds"] = time.perf_counter() - t0
    report["cpu_seconds"] = time.process_time() - c0
    from skinsuction import __version__

    report["skinsuction_version"] = __version__
    report["created_utc"] = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")
    return report


# --------------------------------------------------------------------- the report
def _report(run, base, candidates: list, source) -> dict:
    """The report's input, geometry, noise, baseline, data and candidates."""
    from ._creep import untestable_on_ramps

    data, fd, probes = run.data, run.fd, run.probes
    return {
        "input": {**(source or {}), "probes_mm": [float(p) for p in probes],
                  "probes_skipped_mm": [float(p) for p in run.skipped],
                  "metadata": dict(getattr(data, "metadata", {}) or {}),
                  "warnings": list(getattr(data, "warnings", ()) or ()) + run.geometry_warnings,
                  "curves": run.data_info},
        "geometry": {**run.geometry.to_dict(), "notes": run.geometry_notes},
        "noise_um": run.noise.sd_um,
        "noise": {**run.noise.to_dict(),
                  "sigma_fitted_um": {f"{p:g}": run.sigma[p] for p in probes},
                  "model_error_um": run.settings.model_error_um},
        "baseline": _baseline_json(run, base),
        "data": {f"{p:g}": {"pressure_mbar": fd[p].pressure_mbar.tolist(),
                            "measured_mm": fd[p].deflection_mm.tolist(),
                            "sigma_um": fd[p].sigma_um} for p in probes},
        "candidates": candidates,
        # causes that a pressure ramp cannot test, and why
        "untestable": [untestable_on_ramps()],
    }


def _baseline_json(run, base) -> dict:
    fit, test = base.fit, base.test
    return {
        "model": BASELINE,
        "parameters": fit.parameters,
        "E_um": fit.E_um,
        "systematic_misfit": test.significant,
        "description": describe_residuals(test, residual_dict(fit, run.fd, False), run.sigma),
        "bic": base.bic,
        "holdout_E_um": base.holdout_E_um,
        "holdout": base.holdout,
        "at_bound": base.bounds,
        "intervals": base.intervals,
        **{k: v for k, v in fit_json(fit, test).items() if k != "parameters"},
        "skin": fitted_skin(run, fit),
    }


def _verdict(base, candidates, best, cause, verdict, ambiguous, beyond) -> dict:
    """The report's verdict: the cause, how it was detected, its gain, the runner-up."""
    ranked = sorted(candidates, key=lambda c: c["bic"])
    runner_up = next((c for c in ranked if best is not None and c is not best), None)
    return {
        "cause": cause,
        # the effects named, in the order added: a ramp names one cause at most
        "effects": [cause] if verdict == "cause_found" else [],
        "verdict": verdict,
        # which test saw the effect: the generic smooth-pattern test of the neo-Hookean
        # residuals, and/or a candidate's own BIC (decisive and removing the misfit)
        "detection": {"pattern_test": bool(base.test.significant),
                      "candidate_bic": any(map(eligible, candidates))},
        "beyond_space": beyond,
        "extended": ({"cause": best["cause"], "parameters": best["parameters"],
                      "intervals": best["intervals"], "E_um": best["E_um"],
                      "skin": best["skin"]} if best else None),
        "gain": ({"E_ratio": best["E_ratio"], "delta_bic": best["delta_bic"],
                  "holdout_ratio": best["holdout_ratio"]} if best else None),
        "runner_up": ({"cause": runner_up["cause"],
                       "bic_above_chosen": runner_up["bic"] - best["bic"],
                       "holdout_E_um": runner_up["holdout_E_um"]}
                      if runner_up else None),
        "ambiguous_with": ambiguous,
    }


def _steps_json(candidates: list, report: dict, step: dict) -> list:
    """The model built effect by effect: each step's options and the effect it added."""
    first = {"step": 1, "from": BASELINE,
             "added": report["effects"][0] if report["effects"] else None,
             "options": [{"effects": [c["cause"]], "delta_chi2": c["delta_chi2"],
                          "delta_bic": c["delta_bic"], "removes_misfit": c["removes_misfit"]}
                         for c in candidates]}
    if not step["tried"]:
        return [first]
    second = {"step": 2, "from": step["parent"],
              "added": step["added"]["added"] if step["added"] else None,
              "options": [{"effects": o["effects"], "delta_chi2": o["delta_chi2"],
                           "delta_bic": o["delta_bic"],
                           "delta_bic_vs_added_alone": o["delta_bic_vs_added_alone"],
                           "removes_misfit": o["removes_misfit"]} for o in step["options"]]}
    return [first, second]


def _spaces_json(spaces: dict) -> dict:
    """What the report records of each space: its reach, mesh and commit."""
    return {name: {"x1d_range_mpa": list(s.spec.x1d_range),
                   "load_max_mbar_per_mpa": s.spec.load_max,
                   "x1h_over_x1d_range": [s.spec.ratio_nodes[0], s.spec.ratio_nodes[-1]],
                   "coordinate_range": ([s.cause.lower, s.cause.upper] if s.cause else None),
                   "mesh": s.spec.mesh,
                   "git_commit": (s.metadata.get("git") or {}).get("commit")}
            for name, s in spaces.items()}


# --------------------------------------------------------------------- a file
def diagnose_file(measured_path, space_dir=None, settings: Settings | None = None,
                  spaces: dict | None = None, *, thickness: dict | None = None,
                  on_demand=None, workers: int = 1, pairs: dict | None = None) -> dict:
    """Read a measured CSV (as ``skinsuction identify`` does) and diagnose it.

    Parameters
    ----------
    measured_path : path-like or MeasuredData
        The measured CSV, or its curves as read
        (:func:`skinsuction.measured.read_measurement`): checked against the
        spaces, not read again.
    space_dir : path-like, optional
        The scale-free space; by default the workflow's build in
        ``results/simulated_space/scale_free`` of the working directory if there
        is one, else the default space shipped with skinsuction
        (:func:`skinsuction.space.resolve_space`).  ``input.space`` of the report
        says which.
    settings : Settings, optional
        Default: ``Settings()``.
    spaces : dict, optional
        The ray spaces already read (from ``space_dir``).
    thickness : dict, optional
        ``dermis_thickness_mm`` ... overriding the file's header lines.
    on_demand : OnDemandRays, bool or "always", optional
        An :class:`skinsuction.space.OnDemandRays`, False to refuse a probe or
        layers the spaces lack, None to read them off the geometry space or solve
        them, "always" to solve every one (the reference).
    workers : int
        Processes that solve rays on demand.
    pairs : dict, optional
        The pair spaces; by default those that go with the space
        (:func:`skinsuction.space.pairs_for`).

    Returns
    -------
    dict
        The report of :func:`diagnose`, with the file's SHA-256 and the space.
    """
    from skinsuction._files import file_sha256
    from skinsuction.measured import MeasuredData, check_against_space, geometry_of, load_measured

    from skinsuction.space import (
        OnDemandRays,
        geometry_file_for,
        pairs_for,
        read_ray_spaces,
        resolve_space,
    )

    if spaces is None or space_dir is not None:
        src = resolve_space(space_dir)
        space_dir, space_info = src.path, src.info()
    else:
        space_info = {"source": "given", "description": "ray spaces given in memory"}
    if spaces is None:
        spaces = read_ray_spaces(space_dir)
    base = spaces[BASELINE]
    sp = base.spec
    data = (measured_path if isinstance(measured_path, MeasuredData)
            else load_measured(measured_path))
    check_against_space(data, available_probes=None if on_demand is not False
                        else list(base.probes_mm),
                        pressure_range_mbar=(0.0, sp.reach_mbar()),
                        range_note=(f"the reach of the scale-free space: p/X1d <= "
                                    f"{sp.load_max:g} mbar/MPa up to X1d = "
                                    f"{sp.x1d_range[1]:g} MPa"))
    source = {"file": data.path, "sha256": file_sha256(data.path),
              "space_dir": str(space_dir) if space_dir is not None else None,
              "space": space_info}
    geometry, warnings = geometry_of(data, **(thickness or {}))
    solver = None
    if on_demand is not False:
        solver = on_demand
        if on_demand in (None, True, "always"):
            solver = OnDemandRays(sp, workers=workers, geometry=geometry_file_for(
                resolve_space(space_dir).path, on_demand if on_demand == "always" else True))
    if pairs is None:
        pairs = pairs_for(space_dir, sp)
    report = diagnose(data, spaces, settings, source=source, geometry=geometry, on_demand=solver,
                      pairs=pairs)
    report["input"]["warnings"] = warnings + report["input"]["warnings"]
    return report
