"""The diagnosis over the physiological domain: confusion matrix and detectability.

One draw (:func:`run_draw`) is a virtual experiment from a seed: X1d
log-uniform over the physiological range, X1h/X1d log-uniform, the noise
uniform, a pressure protocol, and the hidden effect across its physiological
range (:data:`WIDE_DOMAIN`).  It is made by direct FE runs (both probes, the
space's mesh), diagnosed as a user would (``diagnose_file``), and judged
*detectable* or not independently of the diagnosis: the noise-free curves of
the true model are fitted by the best neo-Hookean model (on the same space),
and the effect is detectable when what the neo-Hookean model cannot absorb
would earn the extra parameter against pure noise (chi^2 of that misfit at
least ``-delta_bic + ln n``, the rule's threshold) and, where the rule has its
pattern gate (``Settings.pattern_gate``), forms a pattern the smooth-residual test
sees; each row has both (``detectable_gated``, ``detectable_ungated``) and both
rules' verdicts on the same fits (:func:`~skinsuction.evaluation.under_rule`).  The matrix
is then reported over the detectable draws, with the detectable fraction per cause
(:func:`~skinsuction.evaluation.summarise`, in :mod:`._rates`).  A detectable
cause may still be mimicked by another: every cause is fitted to the same
noise-free curves, and the draw is *distinguishable* when the best other cause
stays at least the tie rule's BIC gap (``ambiguity_bic``) behind the true one
(:func:`_rivals`); the right-cause rate is reported over those draws too.
"""

from __future__ import annotations

import math
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd

from skinsuction.space import BASELINE, NONE, load

from ._solvers import SolverRefused, solver_curves, solver_mesh

__all__ = ["WIDE_DOMAIN", "draw_wide", "domain_from_config", "given_keywords", "run_draw",
           "run_draws", "initial_stress_kpa", "interval_columns"]

#: The physiological domain of the draws (forearm suction studies: E = 129 +- 88 kPa,
#: X1d = E / 6; dermis 0.5-2.5 mm; natural tension up to tens of kPa; Cutometer noise
#: 1-5 µm; protocols to 100 or 300 mbar).  Effect sizes: X2d/X1d log-uniform (the
#: paper's own fit has about 500), t_d uniform in mm, lambda0 uniform.
WIDE_DOMAIN = {
    "x1d_mpa": (0.005, 0.15),
    "x1h_over_x1d": (0.003, 0.1),
    "noise_um": (1.0, 5.0),
    "protocols": ((100.0, 2.0), (300.0, 5.0)),
    "effects": {
        "strain_stiffening": ("log", 1.0, 500.0),
        "dermis_thickness": ("uniform", 0.5, 2.5),
        "hypodermis_thickness": ("log", 0.5, 10.0),
        "pre_tension": ("uniform", 1.01, 1.25),
    },
    # the Cutometer's probe pairs, drawn evenly
    "probe_pairs": ((2.0, 6.0), (4.0, 8.0)),
    # None, or the dermis as measured by ultrasound: true t_d uniform in `range` (mm),
    # given in the file's header with a Gaussian error of `sd` (mm), stated as its sd
    "given_dermis_thickness": None,
    # None, or the hypodermis as measured too: true t_h log-uniform in `range` (mm),
    # given with a Gaussian error of `sd` (mm); hypodermis_thickness is then no cause
    "given_hypodermis_thickness": None,
}


def initial_stress_kpa(lambda0: float, x1d_mpa: float) -> float:
    """In-plane Cauchy stress of an equibiaxial pre-stretch of the incompressible
    neo-Hookean dermis, ``mu (lambda0^2 - lambda0^-4)`` with ``mu = 2 X1d``, in kPa."""
    return 1e3 * 2.0 * x1d_mpa * (lambda0 ** 2 - lambda0 ** -4)


def draw_wide(seed: int, cause, domain=None, load_max=None) -> dict:
    """The parameters of one draw (moduli, ratio, noise, protocol, effect).

    A longer protocol is drawn only where the space reaches it
    (``p_max / X1d <= load_max``); otherwise the first (100 mbar) is used.
    """
    d = {**WIDE_DOMAIN, **(domain or {})}
    rng = np.random.default_rng(np.random.SeedSequence(seed).spawn(1)[0])
    x1d = math.exp(rng.uniform(*np.log(d["x1d_mpa"])))
    ratio = math.exp(rng.uniform(*np.log(d["x1h_over_x1d"])))
    noise = rng.uniform(*d["noise_um"])
    p_max, p_step = d["protocols"][rng.integers(len(d["protocols"]))]
    if load_max is not None and load(p_max, x1d) > load_max:  # beyond the space's reach
        p_max, p_step = d["protocols"][0]
    out = {"x1d": x1d, "ratio": ratio, "noise_um": noise, "p_max": p_max, "p_step": p_step,
           "coordinate": None, "value": None, "probes": (2.0, 6.0), "t_d": 1.0,
           "t_d_given": None, "t_h": 1.0, "t_h_given": None}
    if cause is not None:
        kind, lo, hi = d["effects"][cause.name]
        c = math.exp(rng.uniform(math.log(lo), math.log(hi))) if kind == "log" \
            else rng.uniform(lo, hi)
        out["coordinate"] = c
        out["value"] = float(cause.value(c, x1d))
    # drawn after the rest, so that a draw of the 2 + 6 mm probes is the one of before
    pairs = d.get("probe_pairs") or ((2.0, 6.0),)
    if len(pairs) > 1:
        out["probes"] = tuple(float(q) for q in pairs[rng.integers(len(pairs))])
    else:
        out["probes"] = tuple(float(q) for q in pairs[0])
    given = d.get("given_dermis_thickness")
    if given:
        out["t_d"] = float(rng.uniform(*given["range"]))
        out["t_d_given"] = round(out["t_d"] + float(rng.normal(0.0, given["sd"])), 2)
    # drawn last, so that a draw given the dermis alone is the one of before
    given_h = d.get("given_hypodermis_thickness")
    if given_h:
        out["t_h"] = math.exp(rng.uniform(*np.log(given_h["range"])))
        out["t_h_given"] = round(max(out["t_h"] + float(rng.normal(0.0, given_h["sd"])),
                                     0.1), 2)
    return out


def domain_from_config(domain: dict) -> dict:
    """A draw domain from a workflow config (YAML lists) as :func:`draw_wide` takes it
    (tuples; a given thickness without its sd is not given).

    Examples
    --------
    >>> domain_from_config({"probe_pairs": [[2, 6]],
    ...                     "given_dermis_thickness": {"range": [0.5, 2.5], "sd": 0.1},
    ...                     "given_hypodermis_thickness": {"range": [0.5, 10], "sd": None}})
    {'probe_pairs': ((2.0, 6.0),), 'given_dermis_thickness': {'range': (0.5, 2.5), 'sd': 0.1}}
    """
    out = {k: v for k, v in domain.items()
           if k not in ("probe_pairs", "given_dermis_thickness", "given_hypodermis_thickness")}
    if "probe_pairs" in domain:
        out["probe_pairs"] = tuple(tuple(float(q) for q in pair)
                                   for pair in domain["probe_pairs"])
    for key in ("given_dermis_thickness", "given_hypodermis_thickness"):
        given = domain.get(key)
        if given and given.get("sd") is not None:
            out[key] = {"range": tuple(float(x) for x in given["range"]),
                        "sd": float(given["sd"])}
    return out


def given_keywords(domain=None) -> tuple:
    """The thickness coordinates (``"t_d"``, ``"t_h"``) a domain gives in each file:
    their causes are not drawn and not candidates."""
    d = {**WIDE_DOMAIN, **(domain or {})}
    return tuple(k for k, key in (("t_d", "given_dermis_thickness"),
                                  ("t_h", "given_hypodermis_thickness")) if d.get(key))


def _spaces_of_draw(spaces, d, on_demand):
    """``spaces_for(names=None, window=None)``: the spaces the diagnosis reads for a draw,
    at its probes and given layers (the causes' rays on demand cut to an X1h/X1d
    window, as the diagnosis cuts them)."""
    from skinsuction.space import Geometry, spaces_at

    given = tuple(k for k in ("t_d", "t_h") if d.get(f"{k}_given") is not None)
    g = Geometry(*(d[f"{k}_given"] if k in given else 1.0 for k in ("t_d", "t_h")),
                 given=given, sd={k: d[f"{k}_sd"] for k in given})

    def spaces_for(names=None, window=None):
        chosen = spaces if names is None else {n: spaces[n] for n in names}
        return spaces_at(chosen, d["probes"], g, on_demand,
                         ratio_window=window if on_demand is not None else None)[0]

    return spaces_for


def _detectability(ve, spaces_for, settings, n_points, truth=None):
    """Best neo-Hookean fit to the noise-free true curves: chi^2, E, pattern test;
    for a cause, also how well each other cause mimics it (:func:`_rivals`).
    ``spaces_for``: see :func:`_spaces_of_draw`."""
    from skinsuction.diagnose import FitData, fit_model, misfit_test

    fd = {}
    for probe, m in ve.clean.items():
        p = ve.pressures_mbar
        keep = (p > 0) & np.isfinite(m)
        fd[probe] = FitData(probe, p[keep], np.asarray(m)[keep],
                            math.hypot(ve.noise_um, settings.model_error_um))
    try:
        f = fit_model(spaces_for([BASELINE])[BASELINE], fd, seed=0, repeats=1,
                      window_focusing_options=settings.window_focusing)
    except Exception:  # no neo-Hookean candidate covers the curve: beyond the space
        return {"clean_chi2": math.inf, "clean_E_um": math.nan, "clean_pattern_p": 0.0,
                "detectable": True, "detectable_gated": True, "detectable_ungated": True}
    res = {p: (fd[p].pressure_mbar, f.residual_um[p]) for p in fd}
    sig = {p: fd[p].sigma_um for p in fd}
    t = misfit_test(res, sig, math.inf, settings.degree, settings.alpha)
    threshold = -settings.delta_bic + math.log(n_points)
    out = {"clean_chi2": f.chi2, "clean_E_um": f.E_um, "clean_pattern_p": t.p_value,
           # the rule's own noise-free threshold: a misfit that would earn the extra
           # parameter, and (with the pattern gate) a pattern the smooth test sees
           "detectable_gated": bool(f.chi2 >= threshold and t.significant),
           "detectable_ungated": bool(f.chi2 >= threshold)}
    out["detectable"] = out["detectable_" + ("gated" if settings.pattern_gate else "ungated")]
    if truth is not None and truth != NONE:
        out.update(_rivals(fd, spaces_for, settings, truth, f.theta))
    return out


def _rivals(fd, spaces_for, settings, truth, base_theta):
    """Whether the other causes can tell this one apart, on its noise-free curves.

    Every cause's model (the true one included) is fitted to the noise-free
    curves, from its window focusing and, as in the diagnosis, from the neo-Hookean
    fit at the cause's neutral value (so it never fits worse than that).
    ``rival_gap`` is the chi^2 of the best other cause minus that of the
    true cause: with one extra parameter each, it is the BIC gap a noise-free
    measurement would show.  Below ``ambiguity_bic`` even a perfect diagnosis
    could only report a tie (``ambiguous_with``); noise moves the gap by about
    2 sqrt(gap).
    """
    from skinsuction.identify import IdentificationError

    from skinsuction.diagnose import fit_in_window, fit_model, nested_start, ratio_window

    decades = settings.cause_window_decades
    window = None if decades is None else ratio_window(base_theta, decades)
    spaces = spaces_for(None, window)
    full = spaces[BASELINE].spec.ratio_nodes
    chi2 = {}
    for name, space in spaces.items():
        # the causes the diagnosis would fit: those whose space has every probe
        if name == BASELINE or not all(space.has_probe(p) for p in fd):
            continue
        cause = space.cause
        start = nested_start(base_theta, cause)

        def refit(space, previous=None, start=start):
            return fit_model(space, fd, seed=0, repeats=1,
                             window_focusing_options=settings.window_focusing,
                             starts=[start] if previous is None else [previous.theta, start])

        try:
            f = refit(space)
            if window is not None:
                f = fit_in_window(space, f, full, decades,
                                  lambda w, name=name: (spaces_for([BASELINE, name], w)[name],
                                                        []), refit)[1]
            chi2[name] = f.chi2
        except IdentificationError:  # the cause's space does not cover the curves
            chi2[name] = math.inf
    others = {k: v for k, v in chi2.items() if k != truth}
    rival = min(others, key=others.get) if others else None
    gap = (others[rival] - chi2.get(truth, math.inf)) if rival is not None else math.inf
    return {"own_chi2": chi2.get(truth, math.inf), "rival": rival,
            "rival_chi2": others.get(rival, math.inf), "rival_gap": gap,
            "distinguishable": bool(gap >= settings.ambiguity_bic)}


def _draw_keywords(d: dict, cause, bottom) -> dict:
    """The model keywords of a draw's skin (its layers and hidden effect)."""
    kw = {"x1d": d["x1d"], "x1h": d["ratio"] * d["x1d"], "bottom": bottom}
    kw.update({k: float(d[k]) for k in ("t_d", "t_h") if d[k] != 1.0})
    if cause is not None:
        kw[cause.keyword] = float(d["value"])
    return kw


def _cache_key(d, mesh, solver="space") -> dict:
    """What a cached FE curve must match: the draw's parameters and the mesh (as JSON)."""
    import json

    key = {k: d[k] for k in ("x1d", "ratio", "p_max", "p_step", "value")} | {"mesh": mesh}
    if solver == "calculix":
        key |= {"code": "calculix"}
    if tuple(d.get("probes") or (2.0, 6.0)) != (2.0, 6.0) or d.get("t_d", 1.0) != 1.0:
        key |= {"probes": list(d["probes"]), "t_d": d["t_d"]}
    if d.get("t_h", 1.0) != 1.0:
        key |= {"t_h": d["t_h"]}
    return json.loads(json.dumps(key))


def _cached_clean(cache_dir, truth, seed, d, mesh, solver="space"):
    """The noise-free curves of a draw from ``cache_dir``, if there for these parameters."""
    import json

    if cache_dir is None:
        return None, None
    tag = "" if solver == "space" else f"{solver}_"
    path = Path(cache_dir) / f"{tag}{truth}_{seed}.json"
    if path.exists():
        saved = json.loads(path.read_text())
        if saved.get("key") == _cache_key(d, mesh, solver):
            return path, {float(p): np.array(c, dtype=float) for p, c in saved["clean"].items()}
    return path, None


def _draw_curves(truth, seed, d, cause, spec, p, cache_dir, solver):
    """A draw's noise-free curves: (the solver's mesh, the cache file, the curves, whether
    they came from the cache).  The curves are None where the virtual experiment is to
    solve them on the space's own FE; another solver's are solved here
    (:class:`SolverRefused` where it cannot carry the skin)."""
    fe_mesh = solver_mesh(solver, spec.mesh)
    cache_path, clean = _cached_clean(cache_dir, truth, seed, d, fe_mesh, solver)
    from_cache = clean is not None
    if clean is None and solver != "space":
        clean = solver_curves(solver, _draw_keywords(d, cause, spec.bottom), d["probes"], p,
                              spec.mesh, list(spec.fallback))
    return fe_mesh, cache_path, clean, from_cache


def _save_clean(path, d, mesh, clean, solver="space"):
    import json

    from skinsuction._files import atomic_output

    body = {"key": _cache_key(d, mesh, solver), "clean": {f"{p:g}": [None if not np.isfinite(v) else float(v)
                                              for v in c] for p, c in clean.items()}}
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_output(path) as tmp:
        tmp.write_text(json.dumps(body))


def run_draw(truth: str, seed: int, spaces: dict, settings=None, domain=None,
             cache_dir=None, on_demand=None, solver: str = "space") -> dict:
    """Draw, simulate, diagnose and judge one virtual experiment: one row.

    ``cache_dir``: where the noise-free FE curves of each draw are kept (one JSON
    per draw, keyed by its parameters and mesh), so that a change of the
    diagnosis is re-measured on the same curves without the FE runs.
    ``on_demand``: the solver of the rays of layers the space lacks
    (:class:`skinsuction.space.OnDemandRays`), for draws with a given dermis.
    ``solver``: the virtual experiment's discretisation or FE code (:data:`.OTHER_SOLVERS`).
    """
    from skinsuction.measured import MeasuredDataError

    from skinsuction.diagnose import BeyondSpaceError, Settings, diagnose_file

    from ._virtual import virtual_experiment, write_csv

    # the cross-probe holdout is no part of the decision these draws measure (a third of
    # their cost): left out, it changes no fit (skinsuction.diagnose's seeds)
    settings = replace(settings or Settings(), holdout=False)
    base = spaces[BASELINE]
    cause = None if truth == NONE else spaces[truth].cause
    d = draw_wide(seed, cause, domain, base.spec.load_max)
    full = {**WIDE_DOMAIN, **(domain or {})}
    d["t_d_sd"] = (full.get("given_dermis_thickness") or {}).get("sd")
    d["t_h_sd"] = (full.get("given_hypodermis_thickness") or {}).get("sd")
    p = np.arange(0.0, d["p_max"] + 1e-9, d["p_step"])
    t0 = time.perf_counter()
    try:
        fe_mesh, cache_path, clean, from_cache = _draw_curves(truth, seed, d, cause, base.spec,
                                                              p, cache_dir, solver)
    except SolverRefused as err:
        return {"truth": truth, "seed": seed, "solver": solver, "named": "solver_refused",
                "error": str(err)}
    ve = virtual_experiment(d["x1d"], d["ratio"] * d["x1d"], cause, d["value"],
                            noise_um=d["noise_um"], seed=seed, pressures_mbar=p,
                            mesh=base.spec.mesh, bottom=base.spec.bottom,
                            fallback=list(base.spec.fallback), clean=clean,
                            probes_mm=d["probes"],
                            layers={k: d[k] for k in ("t_d", "t_h") if d[k] != 1.0} or None)
    if cache_path is not None and not from_cache:
        _save_clean(cache_path, d, fe_mesh, ve.clean, solver)
    row = {"truth": truth, "seed": seed, "solver": solver,
           **{k: v for k, v in d.items() if k != "probes"},
           "x1h": ve.x1h, "fe_converged": ve.converged,
           "fe_seconds": time.perf_counter() - t0, "fe_cached": from_cache}
    if truth == "pre_tension":
        row["initial_stress_kpa"] = initial_stress_kpa(d["value"], d["x1d"])
    if not ve.converged:
        row["named"] = "fe_failed"
        return row
    row["probes"] = "+".join(f"{q:g}" for q in d["probes"])
    drawn = _spaces_of_draw(spaces, d, on_demand)
    row.update(_detectability(ve, drawn, settings, 2 * int((p > 0).sum()), truth))
    header = [line for k, name in (("t_d", "dermis"), ("t_h", "hypodermis"))
              if d[f"{k}_given"] is not None
              for line in (f"{name}_thickness_mm: {d[f'{k}_given']:g}",
                           f"{name}_thickness_sd_mm: {d[f'{k}_sd']:g}")]
    with tempfile.TemporaryDirectory() as tmp:
        csv = write_csv(ve, Path(tmp) / "v.csv", header=header)
        try:
            rep = diagnose_file(csv, None, settings, spaces=spaces,
                                on_demand=on_demand if on_demand is not None else False)
        except BeyondSpaceError:
            row.update(named="beyond_space", verdict="beyond_space")
            return row
        except MeasuredDataError as err:
            # the loader refuses the FE curve as a measurement (a plausibility check):
            # a row that says so, never a lost draw
            row.update(named="input_rejected", verdict="input_rejected",
                       error=" ".join(str(err).split()))
            return row
    row.update(named=rep["cause"], verdict=rep["verdict"], cpu_seconds=rep["cpu_seconds"],
               # a second effect (the pair spaces) where one earned its place
               effects=",".join(rep.get("effects") or []),
               wall_seconds=rep["seconds"],
               ambiguous_with=";".join(rep.get("ambiguous_with") or []),
               beyond=";".join(f"{b['model']}:{b['parameter']}:{b['side']}"
                               for b in rep.get("beyond_space") or []),
               noise_est_um=rep["noise_um"],
               base_misfit=rep["baseline"]["systematic_misfit"],
               base_x1d=rep["baseline"]["parameters"]["X1d"],
               base_x1h=rep["baseline"]["parameters"]["X1h"])
    row.update(_rule_columns(rep, settings))
    b = rep["baseline"]
    named = next((c for c in rep["candidates"] if c["cause"] == rep["cause"]), None)
    sym = None if named is None else spaces[named["cause"]].cause.symbol
    if named is not None:
        row.update(ext_x1d=named["parameters"]["X1d"], ext_x1h=named["parameters"]["X1h"],
                   ext_value=named["parameters"][sym], delta_bic=named["delta_bic"])
    # the 95 % intervals of the model the verdict stands on, for their coverage
    row.update(interval_columns((named or b).get("intervals"), sym))
    return row


def _rule_columns(rep, settings) -> dict:
    """The verdict of a diagnosis's fits under either detection rule
    (``Settings.pattern_gate``): ``named_gated``, ``verdict_gated``, ... ``_ungated``."""
    from skinsuction.diagnose import decide

    b, out = rep["baseline"], {}
    for gate, tag in ((True, "gated"), (False, "ungated")):
        _, c, v, amb, _, _ = decide(b["systematic_misfit"], b["bic"], b["at_bound"],
                                    rep["candidates"], replace(settings, pattern_gate=gate))
        out.update({f"named_{tag}": c, f"verdict_{tag}": v, f"ambiguous_with_{tag}": ";".join(amb)})
    return out


def interval_columns(intervals, symbol=None) -> dict:
    """A diagnosis's intervals as flat columns: ``ci_x1d_lo``, ``ci_x1d_hi``,
    ``ci_x1d_open`` (an end at the space's edge), the same for ``x1h`` and for the
    cause's parameter as ``ci_value_*``; nothing where there are none."""
    out = {}
    if not intervals or "error" in intervals:
        return out
    for name, col in (("X1d", "x1d"), ("X1h", "x1h"), (symbol, "value")):
        iv = intervals.get(name) if name else None
        if isinstance(iv, dict) and "lower" in iv:
            out.update({f"ci_{col}_lo": iv["lower"], f"ci_{col}_hi": iv["upper"],
                        f"ci_{col}_open": bool(iv["lower_open"] or iv["upper_open"])})
    return out


_SHARED: dict = {}


def _run_shared(job):
    truth, seed = job
    return run_draw(truth, seed, _SHARED["spaces"], _SHARED["settings"],
                    domain=_SHARED.get("domain"), on_demand=_SHARED.get("on_demand"))


def run_draws(spaces: dict, per_cause: int, seed: int = 1000, settings=None,
              workers: int = 1, progress=None, domain=None, on_demand=None,
              shard: tuple = (0, 1)) -> pd.DataFrame:
    """``per_cause`` draws for ``none`` and every cause of ``spaces``: one row each.

    Seeds are ``seed + 100000 k + i`` for the k-th true cause (``none`` first), as in
    ``benchmarks/diagnose_confusion.py``.  Each draw depends on its seed only, so
    ``workers`` processes (forked: they share the spaces) give the same rows, in the
    same order, as one; and ``shard = (j, n)`` runs every n-th draw from the j-th (the
    causes mixed, so shards cost alike): the n shards' rows, sorted by seed, are the
    rows of one run.  ``progress``: a stream for a :class:`skinsuction.Progress`
    bar (a terminal) or periodic lines (a log).
    """
    from skinsuction._progress import Progress

    given = given_keywords(domain)
    # a given thickness is no cause: the others are drawn
    causes = [n for n in spaces if n != BASELINE
              and not (given and spaces[n].cause.keyword in given)]
    jobs = [(truth, seed + 100000 * k + i)
            for k, truth in enumerate([NONE, *causes]) for i in range(int(per_cause))]
    index, count = (int(v) for v in shard)
    if not 0 <= index < count:
        raise ValueError(f"shard {index} of {count}: want 0 <= shard < count")
    jobs = jobs[index::count]
    bar = Progress(len(jobs), "detectability", "draws", progress) if progress else None
    _SHARED.update(spaces=spaces, settings=settings, domain=domain, on_demand=on_demand)
    rows = []
    try:
        if workers > 1 and len(jobs) > 1:
            import multiprocessing as mp

            with mp.get_context("fork").Pool(workers) as pool:
                for row in pool.imap(_run_shared, jobs, chunksize=1):
                    rows.append(row)
                    if bar:
                        bar.step()
        else:
            for job in jobs:
                rows.append(_run_shared(job))
                if bar:
                    bar.step()
    finally:
        _SHARED.clear()
        if bar:
            bar.close()
    df = pd.DataFrame(rows)
    for col in ("cpu_seconds", "wall_seconds", "verdict", "detectable"):
        if col not in df:
            df[col] = np.nan
    return df
