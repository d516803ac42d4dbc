"""Which skins reach the published Cutometer values: creep alone, or creep with stiffening.

Kawałkiewicz et al. (2021, J Cosmet Dermatol 20:875; Dual MPA 580, face, 75 women)
report R0 0.20-0.33 mm, R2 0.66-0.82, R5 0.60-0.92 and R7 0.37-0.52
(:data:`PUBLISHED_FACE`). This module draws two-layer skins of two models under
the standard mode-1 measurement (:data:`FACE_PROTOCOL`: 2 mm probe, 450 mbar, 3 s
on, 3 s off), solves each with the FE time solver
(:func:`skinsuction.viscoelastic.simulate_history`, not the fast path), reads the
R parameters as the device does (:func:`skinsuction.measured.r_parameters`,
first cycle, Ue and Ur 0.1 s after onset and release) and measures how far each
is from the published box (:func:`box_distance`):

* ``creep``: neo-Hookean layers with a spectrum of one or two Prony terms shared
  by both layers (any moduli, any spectrum within :data:`CREEP_DOMAIN`);
* ``creep+stiffening``: the same with a stiffening dermis, X2d/X1d up to 1000.

Random draws map the region each model covers; a bounded Nelder-Mead search
from the best draws of each model (:func:`closest_skin`) asks for the skin
nearest the box, so that "creep alone misses the box" rests on a search, not
on luck.

Examples
--------
>>> box_distance({"R0": 0.25, "R2": 0.7, "R5": 0.95, "R7": 0.45})  # R5 0.03 above 0.92, of 0.32
0.09375
"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np

from ._time_virtual import mode1_suction, virtual_skin_curve, write_time_csv

__all__ = ["PUBLISHED_FACE", "FACE_PROTOCOL", "CREEP_DOMAIN", "MODELS", "box_distance",
           "skin_of", "draw_parameters", "r_values", "evaluate_draw", "closest_skin",
           "published_ranges_study", "published_ranges_summary", "published_ranges_markdown",
           "target_cost"]

#: Published ranges of the face (Kawałkiewicz et al. 2021), by R parameter.
PUBLISHED_FACE = {"R0": (0.20, 0.33), "R2": (0.66, 0.82), "R5": (0.60, 0.92),
                  "R7": (0.37, 0.52)}

#: The mode-1 measurement of those values: probe, suction, on and off times, cycles.
FACE_PROTOCOL = {"probe_mm": 2.0, "level_mbar": 450.0, "on_s": 3.0, "off_s": 3.0,
                 "cycles": 1}

#: The ranges drawn and searched (log10 bounds): moduli in MPa, tau in s.
CREEP_DOMAIN = {"x1d": (-2.3, -1.0), "ratio": (-3.0, 0.0), "g": (-1.3, 0.7),
                "tau": (-2.0, 1.0), "stiffening": (0.0, 3.0)}

#: The models compared, and how many Prony terms each may carry.
MODELS = ("creep", "creep+stiffening")


def box_distance(r: dict, box: dict = PUBLISHED_FACE) -> float:
    """How far R values lie outside a box: the sum over parameters of the distance to
    the range over the range's width (0 inside every range; NaN counts as far away).

    Parameters
    ----------
    r : dict
        ``{"R0": mm, "R2": ..., ...}``.
    box : dict
        ``{name: (low, high)}`` (default :data:`PUBLISHED_FACE`).

    Returns
    -------
    float
    """
    out = 0.0
    for name, (lo, hi) in box.items():
        v = r.get(name, math.nan)
        if not math.isfinite(v):
            return math.inf
        out += max(lo - v, 0.0, v - hi) / (hi - lo)
    return round(out, 12)


def skin_of(params: dict):
    """The skin of drawn parameters.

    Parameters
    ----------
    params : dict
        ``x1d`` (MPa), ``ratio`` (X1h/X1d), ``g`` and ``tau_s`` (lists, one or
        two terms), ``x2d_over_x1d`` (0: neo-Hookean).

    Returns
    -------
    skinsuction.model.Skin
        Two layers of 1 mm on a fixed bottom sharing the spectrum.
    """
    from skinsuction.model import Prony, Skin

    order = np.argsort(params["tau_s"])
    spectrum = Prony([params["g"][i] for i in order], [params["tau_s"][i] for i in order])
    x1d = params["x1d"]
    return Skin.two_layer(x1d, params["ratio"] * x1d, x2d=params["x2d_over_x1d"] * x1d,
                          spectrum=spectrum)


def _vector_to_params(v, model: str, terms: int) -> dict:
    """Parameters of a search vector (log10 of x1d, ratio, [1 + X2d/X1d], g and tau)."""
    v = list(map(float, v))
    x1d, ratio = 10.0 ** v[0], 10.0 ** v[1]
    k = 2
    stiff = 0.0
    if model == "creep+stiffening":
        stiff, k = 10.0 ** v[2] - 1.0, 3
    g = [10.0 ** v[k + 2 * j] for j in range(terms)]
    tau = [10.0 ** v[k + 2 * j + 1] for j in range(terms)]
    return {"x1d": x1d, "ratio": ratio, "x2d_over_x1d": stiff, "g": g, "tau_s": tau}


def _bounds(model: str, terms: int) -> tuple:
    d = CREEP_DOMAIN
    lo = [d["x1d"][0], d["ratio"][0]] + ([d["stiffening"][0]] if model != "creep" else [])
    hi = [d["x1d"][1], d["ratio"][1]] + ([d["stiffening"][1]] if model != "creep" else [])
    for _ in range(terms):
        lo += [d["g"][0], d["tau"][0]]
        hi += [d["g"][1], d["tau"][1]]
    return np.array(lo), np.array(hi)


def draw_parameters(model: str, seed: int) -> dict:
    """One skin of a model drawn log-uniformly over :data:`CREEP_DOMAIN` (one or two
    Prony terms, even odds; the stiffening ``1 + X2d/X1d`` log-uniform over 1-1000).

    Parameters
    ----------
    model : {"creep", "creep+stiffening"}
    seed : int

    Returns
    -------
    dict
        As :func:`skin_of` takes, with ``model``, ``terms`` and ``seed``.
    """
    if model not in MODELS:
        raise ValueError(f"model must be one of {MODELS}, not {model!r}")
    rng = np.random.default_rng(np.random.SeedSequence([seed, MODELS.index(model)]))
    terms = int(rng.integers(1, 3))
    lo, hi = _bounds(model, terms)
    params = _vector_to_params(rng.uniform(lo, hi), model, terms)
    return {**params, "model": model, "terms": terms, "seed": int(seed)}


def r_values(params: dict, protocol: dict = FACE_PROTOCOL, mesh=None) -> dict:
    """R0-R9 of the first cycle of a noise-free FE mode-1 curve of a skin.

    The curve is sampled at 100 Hz, not rounded, written as a measured time-curve
    file and read back, so the R parameters are those the package reads of a
    measurement (:func:`skinsuction.measured.r_parameters`).

    Parameters
    ----------
    params : dict
        As :func:`skin_of` takes.
    protocol : dict
        :data:`FACE_PROTOCOL`'s keys.
    mesh : dict, optional
        FE mesh settings (default the reference mesh).

    Returns
    -------
    dict
        ``Ue, Uv, Uf, Ur, Ua`` (mm), ``R0``-``R9``; NaN for each if the FE solve stops
        (``fe_stopped`` says why).
    """
    from skinsuction.measured import load_time_curves, r_parameters

    suction = mode1_suction(protocol["level_mbar"], protocol["on_s"], protocol["off_s"],
                            protocol["cycles"], before_s=0.5)
    try:
        t, p, d, _, _ = virtual_skin_curve(skin_of(params), suction,
                                           probe_mm=protocol["probe_mm"], noise_mm=0.0,
                                           resolution_mm=0.0, mesh=mesh)
    except RuntimeError as err:
        return {"fe_stopped": str(err)}
    with tempfile.TemporaryDirectory() as tmp:
        path = write_time_csv(Path(tmp) / "curve.csv", [(protocol["probe_mm"], t, p, d)],
                              header=[f"protocol: mode 1, {protocol['level_mbar']:g} mbar"])
        curve = load_time_curves(path).curves[0]
        row = r_parameters(curve).iloc[0]
    return {k: float(row[k]) for k in ("Ue", "Uv", "Uf", "Ur", "Ua", "R0", "R1", "R2", "R5",
                                       "R6", "R7", "R8")}


def evaluate_draw(params: dict, protocol: dict = FACE_PROTOCOL, mesh=None) -> dict:
    """One row of the benchmark: the parameters, the R values, the distance to the box.

    Parameters
    ----------
    params : dict
        :func:`draw_parameters`'s (or a search's) parameters.
    protocol : dict
    mesh : dict, optional

    Returns
    -------
    dict
        Flat: ``model``, ``terms``, ``x1d``, ``ratio``, ``x2d_over_x1d``, ``g1``,
        ``tau1_s``, ``g2``, ``tau2_s``, the R values, ``distance``, ``inside``.
    """
    r = r_values(params, protocol, mesh)
    row = {k: params.get(k) for k in ("model", "terms", "seed", "x1d", "ratio",
                                      "x2d_over_x1d")}
    for j in range(2):
        row[f"g{j + 1}"] = params["g"][j] if j < len(params["g"]) else 0.0
        row[f"tau{j + 1}_s"] = params["tau_s"][j] if j < len(params["tau_s"]) else math.nan
    row.update(r)
    row["distance"] = box_distance(r)
    row["inside"] = bool(row["distance"] == 0.0)
    return row


def target_cost(row: dict, target: str) -> float:
    """What a search minimises: ``"box"``, the distance to the published box;
    ``"lowest_R5"``, R5 plus 10 times the distance of R0, R2 and R7 to their ranges
    (the lowest R5 a model reaches while the other three stay published).

    Parameters
    ----------
    row : dict
        A row of :func:`evaluate_draw`.
    target : {"box", "lowest_R5"}

    Returns
    -------
    float
        Lower is better; inf where the FE solve stopped.
    """
    if target == "box":
        return row["distance"]
    if target == "lowest_R5":
        rest = {k: v for k, v in PUBLISHED_FACE.items() if k != "R5"}
        r5 = row.get("R5", math.nan)
        return r5 + 10.0 * box_distance(row, rest) if math.isfinite(r5) else math.inf
    raise ValueError(f"target must be 'box' or 'lowest_R5', not {target!r}")


def closest_skin(start: dict, protocol: dict = FACE_PROTOCOL, mesh=None,
                 max_evaluations: int = 60, target: str = "box") -> tuple:
    """The skin of a model best at a target (:func:`target_cost`), by a bounded
    Nelder-Mead search.

    Parameters
    ----------
    start : dict
        A row of :func:`evaluate_draw` (its model and number of terms are kept).
    protocol : dict
    mesh : dict, optional
    max_evaluations : int
        FE solves the search may spend.
    target : {"box", "lowest_R5"}

    Returns
    -------
    (dict, int)
        The best row found (its ``seed`` None) and the FE solves spent.
    """
    from scipy.optimize import minimize

    model, terms = start["model"], int(start["terms"])
    lo, hi = _bounds(model, terms)
    x0 = [math.log10(start["x1d"]), math.log10(start["ratio"])]
    if model == "creep+stiffening":
        x0.append(math.log10(1.0 + start["x2d_over_x1d"]))
    for j in range(terms):
        x0 += [math.log10(start[f"g{j + 1}"]), math.log10(start[f"tau{j + 1}_s"])]
    best = {"row": start}
    solves = [0]

    def cost(v):
        v = np.clip(v, lo, hi)
        params = {**_vector_to_params(v, model, terms), "model": model, "terms": terms,
                  "seed": None}
        row = evaluate_draw(params, protocol, mesh)
        solves[0] += 1
        c = target_cost(row, target)
        if c < target_cost(best["row"], target):
            best["row"] = row
        return c if math.isfinite(c) else 1e3

    minimize(cost, np.clip(x0, lo, hi), method="Nelder-Mead", bounds=list(zip(lo, hi)),
             options={"maxfev": int(max_evaluations), "xatol": 1e-3, "fatol": 1e-4})
    return best["row"], solves[0]


def _evaluate(job):
    params, protocol, mesh = job
    return evaluate_draw(params, protocol, mesh)


def _search(job):
    start, protocol, mesh, max_evaluations, target = job
    row, solves = closest_skin(start, protocol, mesh, max_evaluations, target)
    return {**row, "search_from_seed": start["seed"], "solves": solves, "target": target}


def published_ranges_study(draws: int = 120, seed: int = 0, processes: int = 1,
                           search_starts: int = 3, max_evaluations: int = 60, mesh=None,
                           protocol: dict = FACE_PROTOCOL):
    """Both models' draws and searches (the benchmark of the published ranges).

    Parameters
    ----------
    draws : int
        Skins drawn per model (seeds ``seed .. seed + draws - 1``).
    seed : int
    processes : int
        Worker processes (one FE solve each at a time).
    search_starts : int
        Nelder-Mead searches per model and target (:func:`target_cost`: the box, and
        the lowest R5 with R0, R2, R7 published), from its draws best at it.
    max_evaluations : int
        FE solves per search.
    mesh : dict, optional
        FE mesh settings of every solve.
    protocol : dict

    Returns
    -------
    pandas.DataFrame
        One row per draw (``stage`` "draw") and per search's best (``stage``
        "search"), columns of :func:`evaluate_draw`.
    """
    from multiprocessing import get_context

    import pandas as pd

    jobs = [(draw_parameters(m, seed + k), protocol, mesh) for m in MODELS
            for k in range(int(draws))]
    with get_context("fork").Pool(int(processes)) as pool:
        rows = pool.map(_evaluate, jobs, chunksize=1)
        frame = pd.DataFrame(rows).assign(stage="draw")
        starts = []
        for m in MODELS:
            g = frame[frame["model"] == m]
            for target in ("box", "lowest_R5"):
                cost = g.apply(lambda r: target_cost(r.to_dict(), target), axis=1)
                near = g.loc[cost.nsmallest(int(search_starts)).index]
                starts += [(r, protocol, mesh, max_evaluations, target)
                           for r in near.to_dict("records")]
        found = pool.map(_search, starts, chunksize=1)
    return pd.concat([frame.assign(target=None), pd.DataFrame(found).assign(stage="search")],
                     ignore_index=True)


def published_ranges_summary(frame) -> list:
    """Per model: draws, how many fall inside the box, the nearest skin and what it misses.

    Parameters
    ----------
    frame : pandas.DataFrame
        :func:`published_ranges_study`'s.

    Returns
    -------
    list of dict
        One record per model.
    """
    out = []
    for m in MODELS:
        g = frame[frame["model"] == m]
        draws = g[g["stage"] == "draw"]
        best = g.loc[g["distance"].idxmin()]
        missed = [f"{k} {best[k]:.3f} (published {lo:g}-{hi:g})"
                  for k, (lo, hi) in PUBLISHED_FACE.items() if not lo <= best[k] <= hi]
        # the lowest R5 of any skin whose R0, R2 and R7 are all published
        rest = {k: v for k, v in PUBLISHED_FACE.items() if k != "R5"}
        ok = g[g.apply(lambda r: box_distance(r.to_dict(), rest) == 0.0, axis=1)]
        low = ok.loc[ok["R5"].idxmin()] if len(ok) else None
        out.append({"model": m, "draws": int(len(draws)),
                    "inside": int(draws["inside"].sum()),
                    "inside_any": int(g["inside"].sum()),
                    "lowest_R5": float(low["R5"]) if low is not None else math.nan,
                    "lowest_R5_skin": ({k: low[k] for k in ("x1d", "ratio", "x2d_over_x1d",
                                                            "g1", "tau1_s", "g2", "tau2_s")}
                                       if low is not None else None),
                    "fe_stopped": int(draws["R0"].isna().sum()),
                    "search_solves": int(g["solves"].fillna(0).sum()) if "solves" in g else 0,
                    "nearest_distance": float(best["distance"]),
                    "nearest_stage": best["stage"],
                    **{k: float(best[k]) for k in PUBLISHED_FACE},
                    "nearest_skin": {k: best[k] for k in ("x1d", "ratio", "x2d_over_x1d", "g1",
                                                          "tau1_s", "g2", "tau2_s")},
                    "missed": missed})
    return out


def published_ranges_markdown(frame, settings: dict | None = None, mesh=None) -> str:
    """The benchmark's summary as Markdown: per model, what its nearest skin reaches.

    Parameters
    ----------
    frame : pandas.DataFrame
        :func:`published_ranges_study`'s rows.
    settings : dict, optional
        The study's settings, recorded under the table.
    mesh : dict, optional
        The FE mesh settings, recorded too.

    Returns
    -------
    str
    """
    from skinsuction.results import markdown_table

    rows = []
    for s in published_ranges_summary(frame):
        skin = s["nearest_skin"]
        spectrum = ", ".join(f"g {skin[f'g{j}']:.3g} tau {skin[f'tau{j}_s']:.3g} s"
                             for j in (1, 2) if skin[f"g{j}"])
        rows.append({"model": s["model"], "FE skins drawn": s["draws"],
                     "drawn inside the box": s["inside"],
                     "inside, searches too": s["inside_any"], "FE stopped": s["fe_stopped"],
                     "lowest R5 with R0, R2, R7 published": s["lowest_R5"],
                     "search solves": s["search_solves"],
                     "nearest: distance": s["nearest_distance"],
                     **{f"nearest: {k}": s[k] for k in PUBLISHED_FACE},
                     "nearest skin": (f"X1d {skin['x1d']:.3g} MPa, X1h/X1d {skin['ratio']:.3g}, "
                                      f"X2d/X1d {skin['x2d_over_x1d']:.3g}; {spectrum}"),
                     "misses": "; ".join(s["missed"]) or "nothing"})
    box = ", ".join(f"{k} {lo:g}-{hi:g}" for k, (lo, hi) in PUBLISHED_FACE.items())
    p = FACE_PROTOCOL
    return "\n".join([
        "# The published Cutometer values of the face: creep alone, or with stiffening",
        "",
        f"Published (Kawałkiewicz et al. 2021, face): {box}. FE mode-1 curves, "
        f"{p['probe_mm']:g} mm probe, {p['level_mbar']:g} mbar, {p['on_s']:g} s on / "
        f"{p['off_s']:g} s off; R read 0.1 s after onset and release. Distance: the sum "
        "over R0, R2, R5, R7 of the distance outside each range over its width.",
        "",
        markdown_table(rows, digits=3),
        "",
        f"Settings: {settings or {}}; mesh: {mesh or {}}.",
        "",
    ])
