"""Running a study: discover the measurements, analyse each, write the outputs."""

from __future__ import annotations

import datetime as _dt
import json
import math
import time
from pathlib import Path

import numpy as np

from skinsuction._progress import Progress

from ._compare import compare_groups

__all__ = ["discover", "run_study", "study_rows", "RESULT_COLUMNS"]

#: Result columns of curves.parquet (ids come first; an id with one of these names
#: is renamed ``id_<name>``).
RESULT_COLUMNS = (
    "row", "source", "sha256", "probes_mm", "objective", "n_points",
    "dermis_thickness_mm", "hypodermis_thickness_mm", "layers_given",
    "x1d_mpa", "x1d_lower_mpa", "x1d_upper_mpa", "x1d_lower_open", "x1d_upper_open",
    "x1h_mpa", "x1h_lower_mpa", "x1h_upper_mpa", "x1h_lower_open", "x1h_upper_open",
    "e_dermis_kpa", "e_dermis_lower_kpa", "e_dermis_upper_kpa", "correlation_x1d_x1h",
    "E_um", "noise_um", "noise_method", "misfit_scale", "at_bound",
    "systematic_misfit", "misfit_p_value", "cause", "verdict", "ambiguous_with",
    "extra_parameter", "extra_unit", "extra_value", "extra_lower", "extra_upper",
    "gain_E_ratio", "delta_bic",
    # time curves: the spectrum, the instantaneous moduli, the R parameters (mean over the
    # cycles of the mode-1 curves) and the fit quality
    "protocol", "prony_terms", "g_1", "g_1_lower", "g_1_upper", "tau_1_s", "tau_1_lower_s",
    "tau_1_upper_s", "g_2", "tau_2_s", "x1d_instantaneous_mpa", "x1h_instantaneous_mpa",
    "Ue", "Uv", "Uf", "Ur", "Ua", "R0", "R1", "R2", "R3", "R4", "R5", "R6", "R7", "R8", "R9",
    "reduced_chi2",
    "warnings", "error", "seed", "seconds",
)

MANIFESTS = ("manifest.csv", "manifest.yaml", "manifest.yml")


def _sha256(path) -> str | None:
    from skinsuction._files import file_sha256

    try:
        return file_sha256(path)
    except OSError:
        return None


def _manifest(folder: Path) -> dict:
    """``{file name: {id: value}}`` from the folder's manifest, if any."""
    for name in MANIFESTS:
        path = folder / name
        if not path.exists():
            continue
        if path.suffix == ".csv":
            import pandas as pd

            table = pd.read_csv(path, dtype=str, keep_default_na=False)
            if "file" not in table.columns:
                raise ValueError(f"{path}: a manifest needs a 'file' column")
            return {r.pop("file"): r for r in table.to_dict("records")}
        import yaml

        try:
            data = yaml.safe_load(path.read_text(encoding="utf-8")) or {}
        except yaml.YAMLError as err:
            raise ValueError(f"{path}: not valid YAML ({' '.join(str(err).split())})") from None
        if not isinstance(data, dict):
            raise ValueError(f"{path}: the manifest must map file names to ids")
        return {str(k): {str(a): str(b) for a, b in (v or {}).items()} for k, v in data.items()}
    return {}


def discover(path, *, available_probes=None, pressure_range_mbar=None, range_note=None) -> list:
    """The measurements of a study: ``[(StudyEntry, sha256)]`` in a stable order.

    ``path`` is a folder (its ``*.csv`` files, sorted, subfolders included, the
    manifest excluded) or one CSV.  Each entry's ids include ``file`` (the path
    relative to the folder).
    """
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such study folder or file")
    if path.is_dir():
        manifest = _manifest(path)
        files = sorted(p for p in path.rglob("*.csv") if p.name not in MANIFESTS)
        if not files:
            raise ValueError(f"{path}: no .csv files in the study folder")
    else:
        manifest, files = {}, [path]
    from skinsuction.measured import MeasuredDataError, StudyEntry, read_measurement

    out = []
    for f in files:
        rel = f.relative_to(path).as_posix() if path.is_dir() else f.name
        ids = {"file": rel, **manifest.get(rel, manifest.get(f.name, {}))}
        sha = _sha256(f)
        try:  # a ramp table's bad measurement is an entry; a bad time file raises
            loaded = read_measurement(f, table=True, ids=ids, available_probes=available_probes,
                                      pressure_range_mbar=pressure_range_mbar,
                                      range_note=range_note)
        except MeasuredDataError as err:
            out.append((StudyEntry(dict(ids), None, str(err), str(f)), sha))
            continue
        if isinstance(loaded, list):
            out += [(entry, sha) for entry in loaded]
        else:
            out.append((_time_entry(f, ids, loaded), sha))
    return out


def _time_entry(path, ids, data):
    """A time-curve file as one measurement (its ``# key: value`` lines are ids); a
    file of several subjects in one long table with ``time_s`` is not read (yet)."""
    from skinsuction.measured import StudyEntry
    from skinsuction.measured._geometry import SD_KEYS

    geometry_keys = set(SD_KEYS) | set(SD_KEYS.values())
    meta = {k: v for k, v in data.metadata.items() if k not in geometry_keys}
    return StudyEntry({**meta, **ids}, data, None, str(path))


def _is_time_data(data) -> bool:
    return bool(data.curves) and hasattr(data.curves[0], "time_s")


def _analyse_time(row, entry, ctx, seed, t0):
    """The row of a time-curve measurement: moduli, spectrum, R parameters."""
    from skinsuction.identify.time_curves import identify_time_data, write_time_identification

    data = entry.data
    try:
        ident = identify_time_data(data, ctx["space"], repeats=ctx["repeats"], seed=seed,
                                   level=ctx["level"], terms=ctx.get("terms", 1))
    except ValueError as err:
        row["error"] = f"{entry.source}: {' '.join(str(err).split())}"
        row["seconds"] = time.perf_counter() - t0
        return row
    iv = ident["intervals"]
    g, tau = ident["g"], ident["tau_s"]
    row.update({"objective": "time curves, joint", "x1d_mpa": ident["X1d"],
                "x1h_mpa": ident["X1h"], "e_dermis_kpa": 6e3 * ident["X1d"],
                "noise_um": float(np.mean(ident["noise"]["sd_um"])),
                "noise_method": ident["noise"]["method"],
                "misfit_scale": iv.get("misfit_scale"),
                "correlation_x1d_x1h": (iv.get("correlation") or {}).get("X1d,X1h"),
                "at_bound": ",".join(k for k, f in ident["at_bound"].items() if f["at_bound"]),
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
                "reduced_chi2": ident["fit_quality"]["reduced_chi2"]})
    cycles = ident["r_parameters"]["mode1"]
    for k in ("Ue", "Uv", "Uf", "Ur", "Ua", *(f"R{i}" for i in range(10))):
        vals = [c[k] for c in cycles if c.get(k) is not None and np.isfinite(c[k])]
        row[k] = float(np.mean(vals)) if vals else None
    g_ = ident["geometry"]
    row.update({"dermis_thickness_mm": g_["dermis_thickness_mm"],
                "hypodermis_thickness_mm": g_["hypodermis_thickness_mm"],
                "layers_given": ",".join(g_["given"])})
    warnings = list(ident["warnings"])
    diag = None
    if ctx.get("ray_spaces") is not None:
        from skinsuction.diagnose._time import diagnose_time_data

        try:
            diag = diagnose_time_data(data, ctx["space"], ctx["settings"].__class__(
                **{**ctx["settings"].__dict__, "seed": seed}))
            row.update({"systematic_misfit": bool(diag["decision"]["elastic_misfits"]),
                        "misfit_p_value": diag["elastic"]["misfit_p"],
                        "cause": diag["named"], "verdict": diag["verdict"],
                        "delta_bic": diag["gain"]["delta_bic"]})
        except ValueError as err:
            warnings.append(f"diagnosis failed: {' '.join(str(err).split())}")
    row["warnings"] = "; ".join(warnings)
    row["seconds"] = time.perf_counter() - t0
    if ctx.get("reports_dir") is not None:
        out = Path(ctx["reports_dir"]) / f"{row['row']:05d}"
        write_time_identification(ident, out / "identification")
        if diag is not None:
            from skinsuction.diagnose._time import write_time_report

            write_time_report(diag, out / "diagnosis")
    return row


# ------------------------------------------------------------------ one measurement
_CTX: dict = {}


def _init(ctx):
    _CTX.clear()
    _CTX.update(ctx)


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


def _analyse(job):
    """Identify (and diagnose) one measurement; never raises: errors become the row's."""
    index, entry, sha = job
    from skinsuction.identify.measured_fit import identify_data, write_identification

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
    if _is_time_data(data):
        return _analyse_time(row, entry, ctx, seed, t0)
    ident = diag = None
    try:
        kw = _objective_for(data)
        ident = identify_data(data, ctx["space"], repeats=ctx["repeats"], seed=seed,
                              level=ctx["level"], **kw)
    except ValueError as err:
        row["error"] = f"{entry.source}: {' '.join(str(err).split())}"
        row["seconds"] = time.perf_counter() - t0
        return row
    est, iv = ident["estimate"], ident["intervals"] or {}
    row.update({"objective": ident["settings"]["objective"]
                + (f" {kw['probe_mm']:g} mm" if "probe_mm" in kw else ""),
                "x1d_mpa": est["x1d_mpa"], "x1h_mpa": est["x1h_mpa"],
                "e_dermis_kpa": 6e3 * est["x1d_mpa"],
                "E_um": ident["E"]["at_estimate"],
                "noise_um": (ident["noise"] or {}).get("sd_um"),
                "noise_method": (ident["noise"] or {}).get("method"),
                "misfit_scale": iv.get("misfit_scale"),
                "correlation_x1d_x1h": (iv.get("correlation") or {}).get("X1d,X1h"),
                "at_bound": ",".join(k for k, f in ident["at_bound"].items() if f["at_bound"]),
                **_interval_columns("x1d", iv.get("X1d")),
                **_interval_columns("x1h", iv.get("X1h"))})
    if iv.get("X1d"):
        row["e_dermis_lower_kpa"] = 6e3 * iv["X1d"]["lower"]
        row["e_dermis_upper_kpa"] = 6e3 * iv["X1d"]["upper"]
    warnings = list(ident["warnings"])
    g = ident["geometry"]
    row.update({"dermis_thickness_mm": g["dermis_thickness_mm"],
                "hypodermis_thickness_mm": g["hypodermis_thickness_mm"],
                "layers_given": ",".join(g["given"])})
    if ctx.get("ray_spaces") is not None:
        from skinsuction.diagnose._diagnose import diagnose

        try:
            diag = diagnose(data, ctx["ray_spaces"], ctx["settings"].__class__(
                **{**ctx["settings"].__dict__, "seed": seed}),
                source={"file": entry.source, "sha256": sha},
                on_demand=ctx["space"].on_demand)
            row.update(_diagnosis_columns(diag))
        except ValueError as err:
            warnings.append(f"diagnosis failed: {' '.join(str(err).split())}")
    row["warnings"] = "; ".join(warnings)
    row["seconds"] = time.perf_counter() - t0
    if ctx.get("reports_dir") is not None:
        out = Path(ctx["reports_dir"]) / f"{index:05d}"
        write_identification(ident, out / "identification")
        if diag is not None:
            from skinsuction.diagnose._report import write_report

            write_report(diag, out / "diagnosis")
    return row


def _diagnosis_columns(d: dict) -> dict:
    base = d["baseline"]
    out = {"systematic_misfit": bool(base["systematic_misfit"]),
           "misfit_p_value": base["misfit_test"]["p_value"],
           "cause": d["cause"], "verdict": d["verdict"],
           "ambiguous_with": ",".join(d.get("ambiguous_with") or [])}
    chosen = next((c for c in d["candidates"] if c["cause"] == d["cause"]), None)
    if chosen is not None:
        x = chosen["extra_parameter"]
        ci = (chosen.get("intervals") or {}).get(x["symbol"]) or {}
        out.update({"extra_parameter": x["symbol"], "extra_unit": x["unit"],
                    "extra_value": x["value"], "extra_lower": ci.get("lower"),
                    "extra_upper": ci.get("upper"),
                    "gain_E_ratio": chosen["E_ratio"], "delta_bic": chosen["delta_bic"]})
    return out


# ------------------------------------------------------------------ the study
def study_rows(entries, *, space, ray_spaces=None, settings=None, repeats: int = 2,
               seed: int = 0, level: float = 0.95, workers: int = 1, reports_dir=None,
               progress=None) -> list:
    """Rows (dicts) of :data:`RESULT_COLUMNS` plus ids, one per entry of :func:`discover`."""
    ctx = {"space": space, "ray_spaces": ray_spaces, "settings": settings,
           "repeats": int(repeats), "seed": int(seed), "level": float(level),
           "reports_dir": reports_dir}
    jobs = [(i, e, sha) for i, (e, sha) in enumerate(entries)]
    bar = Progress(len(jobs), "study", "measurements", progress) if progress is not False else None
    rows = []
    if workers > 1 and len(jobs) > 1:
        import multiprocessing as mp

        # fork: the workers share the spaces read once by the parent
        with mp.get_context("fork").Pool(workers, initializer=_init, initargs=(ctx,)) as pool:
            for row in pool.imap(_analyse, jobs, chunksize=1):
                rows.append(row)
                if bar:
                    bar.step()
    else:
        _init(ctx)
        for job in jobs:
            rows.append(_analyse(job))
            if bar:
                bar.step()
    out = []
    for (entry, _), row in zip(entries, rows):
        ids = {(f"id_{k}" if k in RESULT_COLUMNS else k): str(v) for k, v in entry.ids.items()}
        out.append({**ids, **row})
    return out


def _frame(rows):
    import pandas as pd

    df = pd.DataFrame(rows)
    for c in RESULT_COLUMNS:
        if c not in df.columns:
            df[c] = None
    id_cols = [c for c in df.columns if c not in RESULT_COLUMNS]
    df = df[id_cols + list(RESULT_COLUMNS)]
    for c in ("x1d_lower_open", "x1d_upper_open", "x1h_lower_open", "x1h_upper_open",
              "systematic_misfit"):
        df[c] = df[c].astype("boolean")
    for c in RESULT_COLUMNS:
        if df[c].dtype == object and c not in ("systematic_misfit",):
            vals = [v for v in df[c] if v is not None and not (isinstance(v, float)
                                                                and math.isnan(v))]
            if vals and all(isinstance(v, (int, float, np.number)) and not isinstance(v, bool)
                            for v in vals):
                df[c] = df[c].astype("float64")
            elif not vals or all(isinstance(v, str) for v in vals):
                df[c] = df[c].astype("string")
    return df, id_cols


# ------------------------------------------------------------------ writing
def _md_table(rows, cols):
    head = "| " + " | ".join(cols) + " |\n|" + "---|" * len(cols) + "\n"
    body = ""
    for r in rows:
        cells = []
        for c in cols:
            v = r.get(c)
            cells.append("" if v is None or (isinstance(v, float) and math.isnan(v)) else
                         (f"{v:.3g}" if isinstance(v, float) else str(v)))
        body += "| " + " | ".join(cells) + " |\n"
    return head + body


def _space_text(meta, markdown: bool = True) -> str:
    """The study's space, in words: its description, and its path unless given."""
    desc = meta.get("space_description")
    if not desc:
        return str(meta["space"])
    q = "`" if markdown else ""
    return desc if meta.get("space_source") == "given" else f"{desc} ({q}{meta['space']}{q})"


def _summary_md(df, id_cols, comparison, notes, meta) -> str:
    n, errors = len(df), df[df["error"].notna()]
    lines = [f"# Study {meta['name']}", "",
             f"{n} measurements from {meta['path']}: {n - len(errors)} identified, "
             f"{len(errors)} with an error. Identification with 95 % profile-likelihood "
             f"intervals on {_space_text(meta)}; diagnosis: "
             f"{'yes' if meta['diagnose'] else 'no'}. "
             f"{meta['seconds']:.1f} s on {meta['workers']} worker(s).", ""]
    if "group" in df.columns:
        lines += ["## X1d per group", "",
                  "| group | visit | n | median X1d (MPa) | IQR (MPa) | median interval width |",
                  "|---|---|---|---|---|---|"]
        keys = ["group"] + (["visit"] if "visit" in df.columns else [])
        for key, g in df[df["x1d_mpa"].notna()].groupby(keys):
            key = key if isinstance(key, tuple) else (key,)
            x = g["x1d_mpa"].astype(float)
            w = ((g["x1d_upper_mpa"] - g["x1d_lower_mpa"]) / g["x1d_mpa"]).astype(float)
            lines.append(f"| {key[0]} | {key[1] if len(key) > 1 else ''} | {len(g)} | "
                         f"{x.median():.4g} | {x.quantile(0.25):.3g}-{x.quantile(0.75):.3g} | "
                         f"{100 * w.median():.2g} % |")
        lines.append("")
    lines += ["## Group comparison", "", *[f"- {t}" for t in notes], "",
              _md_table(comparison, ["group", "comparison", "test", "n", "median_change_percent",
                                     "ci_low_percent", "ci_high_percent", "p_value",
                                     "effect_size"]),
              "median_change_percent: median change of X1d in % (between groups: difference "
              "of the median changes); ci: bootstrap 95 % interval; effect size: rank-biserial "
              "correlation.", ""]
    if df["cause"].notna().any():
        lines += ["## Named causes (diagnosis)", ""]
        key = "group" if "group" in df.columns else None
        tab = (df.groupby(key)["cause"].value_counts().unstack(fill_value=0) if key
               else df["cause"].value_counts().to_frame().T)
        lines += ["| " + (key or "") + " | " + " | ".join(tab.columns) + " |",
                  "|---|" + "---|" * len(tab.columns)]
        for idx, r in tab.iterrows():
            lines.append(f"| {idx} | " + " | ".join(str(int(v)) for v in r) + " |")
        lines.append("")
    if len(errors):
        lines += ["## Errors", ""]
        for _, r in errors.iterrows():
            ids = ", ".join(f"{c}={r[c]}" for c in id_cols if r[c] is not None
                            and str(r[c]) not in ("", "<NA>", "nan"))
            lines.append(f"- {ids}: {r['error']}")
        lines.append("")
    lines += [f"Written {meta['created_utc']} by skinsuction {meta['version']}.", ""]
    return "\n".join(lines)


def run_study(path, out_dir, *, space_dir=None,
              diagnose: bool = True, repeats: int = 2, seed: int = 0, level: float = 0.95,
              workers: int = 1, reports: bool = False, name: str | None = None,
              diagnosis_settings: dict | None = None, figures: bool = True,
              progress=None, space=None, ray_spaces=None) -> dict:
    """Identify (and diagnose) every measurement of a study and write its outputs.

    Parameters
    ----------
    path : path-like
        A folder of measured CSVs or one long CSV (see the module docstring).
    out_dir : path-like
        Output folder (``curves.parquet``, ``comparison.csv``, ``summary.md``,
        figures, ``study.json`` with the settings and versions).
    space_dir : path-like, optional
        The scale-free simulated space.  Default: the workflow's build in
        ``results/simulated_space/scale_free`` of the working directory if there
        is one, else the default space shipped with skinsuction
        (:func:`skinsuction.space.resolve_space`); ``study.json`` (``space_source``,
        ``space_description``) and ``summary.md`` say which.
    diagnose : bool
        Diagnose every measurement too (slower: seconds each).
    repeats, seed, level :
        Window focusing runs per identification, the study's seed (measurement
        ``i`` uses ``seed + i``), the confidence level of the intervals.
    workers : int
        Processes (each measurement is independent).
    reports : bool
        Also write the identification and diagnosis files of each measurement.
    space, ray_spaces : optional
        A :class:`skinsuction.space.LoadedSpace` and the ray spaces
        ``{name: RaySpace}`` instead of reading ``space_dir`` (tests, notebooks).

    Returns
    -------
    dict
        Paths written, counts and timings.

    Examples
    --------
    Two subjects, two visits each, identified (not diagnosed) on a small grid
    space filled by the analytic surrogate; the third file is broken and
    becomes a row with its error:

    >>> import pathlib, tempfile
    >>> import pandas as pd
    >>> from skinsuction.identify import surrogate_deflection, write_surrogate_space
    >>> root = pathlib.Path(tempfile.mkdtemp())
    >>> p = [0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0, 90.0, 100.0]
    >>> write_surrogate_space(root / "space.parquet", [0.01, 0.02, 0.03, 0.04, 0.05],
    ...                       [1e-4, 3e-4, 5e-4, 7e-4, 9e-4], p)
    >>> (root / "study").mkdir()
    >>> for subject, x1d in (("S1", 0.025), ("S2", 0.035)):
    ...     for visit, f in ((1, 1.0), (2, 1.2)):
    ...         m = surrogate_deflection(x1d * f, 5e-4, p, 6.0)
    ...         text = f"# subject: {subject}\\n# visit: {visit}\\nprobe_mm,pressure_mbar,deflection_mm\\n"
    ...         text += "".join(f"6,{a:g},{b:.6f}\\n" for a, b in zip(p, m))
    ...         _ = (root / "study" / f"{subject}_v{visit}.csv").write_text(text)
    >>> _ = (root / "study" / "S3_v1.csv").write_text("probe_mm;pressure_mbar\\n")
    >>> r = run_study(root / "study", root / "out", space_dir=root / "space.parquet",
    ...               diagnose=False, figures=False, progress=False)
    >>> rows = pd.read_parquet(root / "out" / "curves.parquet")
    >>> len(rows), int(rows["error"].notna().sum())
    (5, 1)
    >>> truth = [0.025, 0.03, 0.035, 0.042]  # within the error of this coarse 5 x 5 grid:
    >>> est = rows.dropna(subset=["x1d_mpa"])["x1d_mpa"].to_numpy()
    >>> bool(abs(est / truth - 1).max() < 0.03)
    True
    """
    from skinsuction import __version__
    from skinsuction._files import atomic_output
    from skinsuction.space import load_space, resolve_space

    t0 = time.perf_counter()
    if not Path(path).exists():
        raise FileNotFoundError(f"{path}: no such study folder or file")
    if space is None or space_dir is not None or (diagnose and ray_spaces is None):
        src = resolve_space(space_dir)
        space_dir, space_info = src.path, src.info()
    else:
        space_info = {"source": "given", "description": "a space given in memory"}
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    space = space if space is not None else load_space(space_dir)
    entries = discover(path, available_probes=space.available_probes,
                       pressure_range_mbar=space.pressure_range(list(space.spaces)),
                       range_note=space.range_note(list(space.spaces)))
    settings = None
    if not diagnose:
        ray_spaces = None
    else:
        from skinsuction.diagnose._diagnose import Settings
        from skinsuction.space import read_ray_spaces

        ray_spaces = ray_spaces if ray_spaces is not None else read_ray_spaces(space_dir)
        # the study's default: one window focusing run per fit, no holdout (seconds saved
        # per measurement); any decision or fit key of the configuration overrides
        settings = Settings.from_config(None, {"holdout": False, "repeats": 1,
                                               **(diagnosis_settings or {})}, level=level)
    rows = study_rows(entries, space=space, ray_spaces=ray_spaces, settings=settings,
                      repeats=repeats, seed=seed, level=level, workers=workers,
                      reports_dir=(out / "reports") if reports else None, progress=progress)
    df, id_cols = _frame(rows)
    comparison, notes = compare_groups(df, seed=seed)
    seconds = time.perf_counter() - t0
    meta = {"name": name or Path(path).stem, "path": str(path), "space": str(space_dir),
            "space_sha256": space.info.get("sha256"),
            "space_source": space_info["source"],
            "space_description": space_info["description"],
            "space_shipped": space_info.get("shipped"), "diagnose": bool(diagnose),
            "repeats": int(repeats), "seed": int(seed), "level": float(level),
            "workers": int(workers), "seconds": seconds, "version": __version__,
            "created_utc": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
            "measurements": int(len(df)), "errors": int(df["error"].notna().sum()),
            "diagnosis_settings": settings.__dict__ if settings is not None else None}
    paths = {"curves": out / "curves.parquet", "comparison": out / "comparison.csv",
             "summary": out / "summary.md", "study": out / "study.json"}
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pa.Table.from_pandas(df, preserve_index=False)
    table = table.replace_schema_metadata({**(table.schema.metadata or {}),
                                           b"skinsuction": json.dumps(meta, default=str).encode()})
    with atomic_output(paths["curves"]) as tmp:
        pq.write_table(table, tmp)
    import pandas as pd

    with atomic_output(paths["comparison"]) as tmp:
        pd.DataFrame(comparison).to_csv(tmp, index=False)
    with atomic_output(paths["summary"]) as tmp:
        tmp.write_text(_summary_md(df, id_cols, comparison, notes, meta), encoding="utf-8")
    with atomic_output(paths["study"]) as tmp:
        tmp.write_text(json.dumps({**meta, "comparison": comparison, "notes": notes},
                                  indent=1, default=str) + "\n", encoding="utf-8")
    if figures:
        from skinsuction.figures.cohort import write_study_figures

        paths.update(write_study_figures(df, out))
    return {"paths": {k: str(v) for k, v in paths.items()}, "space": _space_text(meta, markdown=False),
            "measurements": int(len(df)),
            "errors": meta["errors"], "seconds": seconds, "comparison": comparison,
            "notes": notes}
