"""The per-curve work of a study: each measurement identified, diagnosed, made a row.

:func:`study_rows` hands every entry of :func:`skinsuction.cohort.discover` to
:func:`_analyse` (in worker processes if asked), which never raises: a
measurement that cannot be identified is a row with its error, a diagnosis that
fails is a warning of its row.  A pressure ramp is identified with intervals
(:func:`_analyse_ramp`), a time-curve file jointly over its curves
(:func:`_analyse_time`); each can be diagnosed and write its reports.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from skinsuction._progress import Progress

__all__ = ["RESULT_COLUMNS", "study_rows"]

#: Result columns of curves.parquet (ids come first; an id with one of these names
#: is renamed ``id_<name>``).
RESULT_COLUMNS = (
    "row", "source", "sha256", "probes_mm", "objective", "n_points",
    "dermis_thickness_mm", "hypodermis_thickness_mm", "layers_given",
    "x1d_mpa", "x1d_lower_mpa", "x1d_upper_mpa", "x1d_lower_open", "x1d_upper_open",
    "x1h_mpa", "x1h_lower_mpa", "x1h_upper_mpa", "x1h_lower_open", "x1h_upper_open",
    "e_dermis_kpa", "e_dermis_lower_kpa", "e_dermis_upper_kpa", "correlation_x1d_x1h",
    "E_um", "noise_um", "noise_method", "misfit_scale", "at_bound",
    "systematic_misfit", "misfit_p_value", "cause", "effects", "verdict", "ambiguous_with",
    "extra_parameter", "extra_unit", "extra_value", "extra_lower", "extra_upper",
    # a ramp's second effect (the pair's fit; extra_* are then the first effect's in it)
    "extra2_parameter", "extra2_unit", "extra2_value", "extra2_lower", "extra2_upper",
    "gain_E_ratio", "delta_bic",
    # time curves: the spectrum, the instantaneous moduli, the R parameters (mean over the
    # cycles of the mode-1 curves) and the fit quality
    "protocol", "prony_terms", "g_1", "g_1_lower", "g_1_upper", "tau_1_s", "tau_1_lower_s",
    "tau_1_upper_s", "g_2", "tau_2_s", "x1d_instantaneous_mpa", "x1h_instantaneous_mpa",
    "Ue", "Uv", "Uf", "Ur", "Ua", "R0", "R1", "R2", "R3", "R4", "R5", "R6", "R7", "R8", "R9",
    "reduced_chi2",
    "warnings", "error", "seed", "seconds",
)

#: The R parameters of a mode-1 curve, averaged over its cycles in a row.
_R_KEYS = ("Ue", "Uv", "Uf", "Ur", "Ua", *(f"R{i}" for i in range(10)))

# ------------------------------------------------------------------ one measurement
#: The study's context in this process (the spaces, settings, seeds): set once per
#: worker by :func:`_init`, so that a job carries only its measurement.
_CTX: dict = {}


def _init(ctx):
    _CTX.clear()
    _CTX.update(ctx)


def _analyse(job):
    """Identify (and diagnose) one measurement; never raises: errors become the row's."""
    index, entry, sha = job
    t0 = time.perf_counter()
    ctx = _CTX
    seed = int(ctx["seed"]) + index
    row = {"row": index, "source": entry.source, "sha256": sha, "seed": seed,
           "error": entry.error}
    if entry.data is None:
        return row
    data = entry.data
    row["probes_mm"] = ",".join(f"{p:g}" for p in data.probes)
    row["n_points"] = int(sum(len(c) for c in data.curves))
    analyse = _analyse_time if _is_time_data(data) else _analyse_ramp
    return analyse(row, entry, ctx, seed, t0)


def _is_time_data(data) -> bool:
    return bool(data.curves) and hasattr(data.curves[0], "time_s")


def _failed(row, entry, err, t0) -> dict:
    """The row of a measurement that could not be identified."""
    row["error"] = f"{entry.source}: {' '.join(str(err).split())}"
    row["seconds"] = time.perf_counter() - t0
    return row


def _seeded(settings, seed):
    """The diagnosis settings with the measurement's seed."""
    return settings.__class__(**{**settings.__dict__, "seed": seed})


def _finish(row, warnings, t0, ctx, ident, diag, write_identification, write_diagnosis):
    """Close a row (warnings, time) and write its reports if asked."""
    row["warnings"] = "; ".join(warnings)
    row["seconds"] = time.perf_counter() - t0
    if ctx.get("reports_dir") is not None:
        out = Path(ctx["reports_dir"]) / f"{row['row']:05d}"
        write_identification(ident, out / "identification")
        if diag is not None:
            write_diagnosis(diag, out / "diagnosis")
    return row


# ------------------------------------------------------------------ a pressure ramp
def _objective_for(data):
    probes = {round(p, 6) for p in data.probes}
    if {2.0, 6.0} <= probes or len(probes) == 2:
        return {"objective": "weighted"}
    return {"objective": "single", "probe_mm": max(probes)}


def _interval_columns(prefix, iv, unit_scale=1.0, suffix="mpa"):
    if not iv:
        return {}
    return {f"{prefix}_lower_{suffix}": iv["lower"] * unit_scale,
            f"{prefix}_upper_{suffix}": iv["upper"] * unit_scale,
            f"{prefix}_lower_open": bool(iv["lower_open"]),
            f"{prefix}_upper_open": bool(iv["upper_open"])}


def _layer_columns(g) -> dict:
    """The layers the identification used (and which were given)."""
    return {"dermis_thickness_mm": g["dermis_thickness_mm"],
            "hypodermis_thickness_mm": g["hypodermis_thickness_mm"],
            "layers_given": ",".join(g["given"])}


def _at_bound(ident) -> str:
    return ",".join(k for k, f in ident["at_bound"].items() if f["at_bound"])


def _ramp_columns(ident, kw) -> dict:
    """The identification's columns of a pressure ramp: estimates, intervals, E, noise."""
    est, iv = ident["estimate"], ident["intervals"] or {}
    out = {"objective": ident["settings"]["objective"]
           + (f" {kw['probe_mm']:g} mm" if "probe_mm" in kw else ""),
           "x1d_mpa": est["x1d_mpa"], "x1h_mpa": est["x1h_mpa"],
           "e_dermis_kpa": 6e3 * est["x1d_mpa"],
           "E_um": ident["E"]["at_estimate"],
           "noise_um": (ident["noise"] or {}).get("sd_um"),
           "noise_method": (ident["noise"] or {}).get("method"),
           "misfit_scale": iv.get("misfit_scale"),
           "correlation_x1d_x1h": (iv.get("correlation") or {}).get("X1d,X1h"),
           "at_bound": _at_bound(ident),
           **_interval_columns("x1d", iv.get("X1d")),
           **_interval_columns("x1h", iv.get("X1h"))}
    if iv.get("X1d"):
        out["e_dermis_lower_kpa"] = 6e3 * iv["X1d"]["lower"]
        out["e_dermis_upper_kpa"] = 6e3 * iv["X1d"]["upper"]
    return out


def _diagnosis_columns(d: dict) -> dict:
    """The diagnosis's columns of a pressure ramp: misfit, cause, extra parameter, gain."""
    base = d["baseline"]
    out = {"systematic_misfit": bool(base["systematic_misfit"]),
           "misfit_p_value": base["misfit_test"]["p_value"],
           "cause": d["cause"], "effects": ",".join(d.get("effects") or []),
           "verdict": d["verdict"],
           "ambiguous_with": ",".join(d.get("ambiguous_with") or [])}
    chosen = next((c for c in d["candidates"] if c["cause"] == d["cause"]), None)
    added = (d.get("second_effect") or {}).get("added")
    if chosen is not None:
        x = chosen["extra_parameter"]
        model = added or chosen
        ci = (model.get("intervals") or {}).get(x["symbol"]) or {}
        out.update({"extra_parameter": x["symbol"], "extra_unit": x["unit"],
                    "extra_value": model["parameters"][x["symbol"]],
                    "extra_lower": ci.get("lower"), "extra_upper": ci.get("upper"),
                    "gain_E_ratio": d["gain"]["E_ratio"] if added else chosen["E_ratio"],
                    "delta_bic": d["gain"]["delta_bic"] if added else chosen["delta_bic"]})
    if added is not None:
        second = next(c for c in d["candidates"] if c["cause"] == added["added"])
        x = second["extra_parameter"]
        ci = (added.get("intervals") or {}).get(x["symbol"]) or {}
        out.update({"extra2_parameter": x["symbol"], "extra2_unit": x["unit"],
                    "extra2_value": added["parameters"][x["symbol"]],
                    "extra2_lower": ci.get("lower"), "extra2_upper": ci.get("upper")})
    return out


def _analyse_ramp(row, entry, ctx, seed, t0):
    """The row of a pressure ramp: (X1d, X1h) with intervals, then the diagnosis."""
    from skinsuction.identify.measured_fit import identify_data, write_identification

    data = entry.data
    try:
        kw = _objective_for(data)
        ident = identify_data(data, ctx["space"], repeats=ctx["repeats"], seed=seed,
                              level=ctx["level"], **kw)
    except ValueError as err:
        return _failed(row, entry, err, t0)
    row.update(_ramp_columns(ident, kw))
    warnings = list(ident["warnings"])
    row.update(_layer_columns(ident["geometry"]))
    diag = None
    if ctx.get("ray_spaces") is not None:
        from skinsuction.diagnose import diagnose

        try:
            diag = diagnose(data, ctx["ray_spaces"], _seeded(ctx["settings"], seed),
                            source={"file": entry.source, "sha256": row["sha256"]},
                            on_demand=ctx["space"].on_demand, pairs=ctx.get("pair_spaces"))
            row.update(_diagnosis_columns(diag))
        except ValueError as err:
            warnings.append(f"diagnosis failed: {' '.join(str(err).split())}")
    return _finish(row, warnings, t0, ctx, ident, diag, write_identification, _write_report)


def _write_report(diag, out_dir):
    from skinsuction.diagnose import write_report

    write_report(diag, out_dir)


# ------------------------------------------------------------------ time curves
def _time_columns(ident, data) -> dict:
    """The identification's columns of time curves: moduli, spectrum, R parameters."""
    iv = ident["intervals"]
    g, tau = ident["g"], ident["tau_s"]
    out = {"objective": "time curves, joint", "x1d_mpa": ident["X1d"],
           "x1h_mpa": ident["X1h"], "e_dermis_kpa": 6e3 * ident["X1d"],
           "noise_um": float(np.mean(ident["noise"]["sd_um"])),
           "noise_method": ident["noise"]["method"],
           "misfit_scale": iv.get("misfit_scale"),
           "correlation_x1d_x1h": (iv.get("correlation") or {}).get("X1d,X1h"),
           "at_bound": _at_bound(ident),
           **_interval_columns("x1d", iv.get("X1d")),
           **_interval_columns("x1h", iv.get("X1h")),
           "e_dermis_lower_kpa": 6e3 * iv["X1d"]["lower"],
           "e_dermis_upper_kpa": 6e3 * iv["X1d"]["upper"],
           "protocol": ",".join(sorted({c.protocol for c in data.curves})),
           "prony_terms": len(g), "g_1": g[0], "tau_1_s": tau[0],
           "g_1_lower": iv["g_1"]["lower"], "g_1_upper": iv["g_1"]["upper"],
           "tau_1_lower_s": iv["tau_1"]["lower"], "tau_1_upper_s": iv["tau_1"]["upper"],
           "g_2": g[1] if len(g) > 1 else None, "tau_2_s": tau[1] if len(tau) > 1 else None,
           "x1d_instantaneous_mpa": ident["X1d_instantaneous"],
           "x1h_instantaneous_mpa": ident["X1h_instantaneous"],
           "reduced_chi2": ident["fit_quality"]["reduced_chi2"]}
    cycles = ident["r_parameters"]["mode1"]
    for k in _R_KEYS:
        vals = [c[k] for c in cycles if c.get(k) is not None and np.isfinite(c[k])]
        out[k] = float(np.mean(vals)) if vals else None
    return out


def _analyse_time(row, entry, ctx, seed, t0):
    """The row of a time-curve measurement: moduli, spectrum, R parameters, creep."""
    from skinsuction.identify.time_curves import identify_time_data, write_time_identification

    data = entry.data
    try:
        ident = identify_time_data(data, ctx["space"], repeats=ctx["repeats"], seed=seed,
                                   level=ctx["level"], terms=ctx.get("terms", 1))
    except ValueError as err:
        return _failed(row, entry, err, t0)
    row.update(_time_columns(ident, data))
    row.update(_layer_columns(ident["geometry"]))
    warnings = list(ident["warnings"])
    diag = None
    if ctx.get("ray_spaces") is not None:
        from skinsuction.diagnose import diagnose_time_data

        try:
            # the identification's creep fit is the diagnosis's creep model
            diag = diagnose_time_data(data, ctx["space"], _seeded(ctx["settings"], seed),
                                      creep=ident.fitted)
            row.update(_time_diagnosis_columns(diag))
        except ValueError as err:
            warnings.append(f"diagnosis failed: {' '.join(str(err).split())}")
    return _finish(row, warnings, t0, ctx, ident, diag, write_time_identification,
                   _write_time_report)


def _time_diagnosis_columns(diag: dict) -> dict:
    """The diagnosis's columns of a time curve: misfit, the effects, the elastic
    effect's parameter (the final model's, with its interval), the gain."""
    out = {"systematic_misfit": bool(diag["decision"]["elastic_misfits"]),
           "misfit_p_value": diag["elastic"]["misfit_p"],
           "cause": diag["named"], "effects": ",".join(diag.get("effects") or []),
           "verdict": diag["verdict"],
           "ambiguous_with": ",".join(diag.get("ambiguous_with") or []),
           "delta_bic": diag["gain"]["delta_bic"]}
    from skinsuction.diagnose import VISCOELASTIC_CREEP

    final = diag.get("final") or {}
    for name in diag.get("effects") or []:
        if name == VISCOELASTIC_CREEP:  # its spectrum has columns of its own
            continue
        cause = (diag.get("causes") or {}).get(name) or {}
        symbol = (cause.get("parameters") or [None])[0]
        if symbol in (final.get("parameters") or {}):
            ci = (final.get("intervals") or {}).get(symbol) or {}
            out.update({"extra_parameter": symbol, "extra_value": final["parameters"][symbol],
                        "extra_lower": ci.get("lower"), "extra_upper": ci.get("upper")})
    return out


def _write_time_report(diag, out_dir):
    from skinsuction.diagnose import write_time_report

    write_time_report(diag, out_dir)


# ------------------------------------------------------------------ every measurement
def study_rows(entries, *, space, ray_spaces=None, settings=None, repeats: int = 2,
               seed: int = 0, level: float = 0.95, workers: int = 1, reports_dir=None,
               progress=None, pair_spaces=None, checkpoint=None) -> list:
    """One row per measurement of a study: identified (and diagnosed).

    Parameters
    ----------
    entries : list of tuple
        ``(StudyEntry, sha256)`` as :func:`skinsuction.cohort.discover` gives them.
    space : LoadedSpace
        The scale-free space of the identifications.
    ray_spaces : dict, optional
        ``{name: RaySpace}`` of the diagnosis; None: no diagnosis.
    settings : skinsuction.diagnose.Settings, optional
        Of the diagnosis (measurement ``i`` uses ``seed + i``).
    repeats, seed, level :
        Window focusing runs per identification, the study's seed, the level of
        the intervals.
    workers : int
        Processes (forked: they share the spaces read once).
    reports_dir : path-like, optional
        Write each measurement's identification and diagnosis files under
        ``reports_dir/<row>/``.
    progress : optional
        As for :class:`skinsuction.Progress`; False: none.
    pair_spaces : dict, optional
        ``{name: PairRaySpace}``: the ramps' second effect (:func:`skinsuction.diagnose.diagnose`).
    checkpoint : skinsuction.cohort.Checkpoint, optional
        Rows it holds are taken as they are; each new row is added to it as it
        finishes (a run cut short keeps them).

    Returns
    -------
    list of dict
        The ids (renamed ``id_<name>`` where they clash with :data:`RESULT_COLUMNS`)
        then the result columns, in the order of ``entries``.
    """
    ctx = {"space": space, "ray_spaces": ray_spaces, "pair_spaces": pair_spaces,
           "settings": settings,
           "repeats": int(repeats), "seed": int(seed), "level": float(level),
           "reports_dir": reports_dir}
    rows = {}
    jobs = []
    for i, (e, sha) in enumerate(entries):
        done = checkpoint.finished(i, e.source, sha, int(seed) + i) if checkpoint else None
        if done is not None:
            rows[i] = done
        else:
            jobs.append((i, e, sha))
    bar = Progress(len(jobs), "study", "measurements", progress) if progress is not False else None

    def keep(row):
        rows[row["row"]] = row
        if checkpoint is not None:
            checkpoint.add(row)
        if bar:
            bar.step()

    if workers > 1 and len(jobs) > 1:
        import multiprocessing as mp

        # fork: the workers share the spaces read once by the parent
        with mp.get_context("fork").Pool(workers, initializer=_init, initargs=(ctx,)) as pool:
            for row in pool.imap_unordered(_analyse, jobs, chunksize=1):
                keep(row)
    else:
        _init(ctx)
        for job in jobs:
            keep(_analyse(job))
    rows = [rows[i] for i in range(len(entries))]
    out = []
    for (entry, _), row in zip(entries, rows):
        ids = {(f"id_{k}" if k in RESULT_COLUMNS else k): str(v) for k, v in entry.ids.items()}
        out.append({**ids, **row})
    return out
