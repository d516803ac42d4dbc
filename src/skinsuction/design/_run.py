"""Every skin by every design, in worker processes; the files written."""

from __future__ import annotations

import datetime as _dt
import json
import time
from pathlib import Path

import pandas as pd

from ._box import Question
from ._predict import predict_skin
from ._summary import design_markdown, recommend, summarize

__all__ = ["predict_designs", "run_design"]

_CTX: dict = {}


def _init(ctx):
    _CTX.clear()
    _CTX.update(ctx)


def _one(job):
    skin, design = job
    ctx = _CTX
    try:
        return predict_skin(skin, design, ctx["spaces"], ctx["settings"], causes=ctx["causes"],
                            on_demand=ctx["on_demand"], solve_rays=ctx["solve_rays"])
    except Exception as err:  # a skin that cannot be predicted is a row with its error
        return {"design": design.name, "skin": int(skin["skin"]), "beyond_space": False,
                "error": f"{type(err).__name__}: {' '.join(str(err).split())}"}


def predict_designs(skins: pd.DataFrame, designs: list, *, spaces: dict, settings,
                    causes=(), workers: int = 1, on_demand=None, solve_rays=False,
                    progress=None) -> pd.DataFrame:
    """:func:`predict_skin` for every skin and design: one row each (an error is a row's).

    Parameters
    ----------
    skins : pandas.DataFrame
        :meth:`Box.draw` or :func:`skins_from_table`.
    designs : list of Design
    spaces, settings, causes, on_demand, solve_rays :
        As :func:`predict_skin`.
    workers : int
        Processes (forked: they share the spaces read once).

    Returns
    -------
    pandas.DataFrame
    """
    from skinsuction._progress import Progress

    ctx = {"spaces": spaces, "settings": settings, "causes": tuple(causes),
           "on_demand": on_demand, "solve_rays": bool(solve_rays)}
    jobs = [(row._asdict(), d) for d in designs for row in skins.itertuples(index=False)]
    bar = Progress(len(jobs), "design", "predictions", progress) if progress is not False \
        else None
    out = []
    if workers > 1 and len(jobs) > 1:
        import multiprocessing as mp

        with mp.get_context("fork").Pool(workers, initializer=_init, initargs=(ctx,)) as pool:
            for r in pool.imap(_one, jobs, chunksize=4):
                out.append(r)
                if bar:
                    bar.step()
    else:
        _init(ctx)
        for job in jobs:
            out.append(_one(job))
            if bar:
                bar.step()
    df = pd.DataFrame(out)
    if "error" not in df:
        df["error"] = None
    return df


def run_design(skins: pd.DataFrame, designs: list, question: Question, out_dir, *,
               space_dir=None, workers: int = 1, solve_rays: bool = False, source: str = "",
               seed=None, settings=None, figures: bool = True, progress=None) -> dict:
    """Predict every design over the skins, recommend one, write the files.

    Writes ``predictions.csv`` (a row per skin and design), ``designs.csv`` (a row
    per design), ``design.md`` (the table and the recommendation),
    ``design.json`` (the question, the recommendation, the settings, versions) and
    ``precision.png`` (precision against design, one panel per parameter).

    Returns
    -------
    dict
        ``recommendation``, ``summary`` (DataFrame), ``paths``, ``seconds``.
    """
    from skinsuction import __version__
    from skinsuction._files import atomic_output, write_table
    from skinsuction.diagnose import Settings
    from skinsuction.space import BASELINE, OnDemandRays, read_ray_spaces, resolve_space

    t0 = time.perf_counter()
    src = resolve_space(space_dir)
    spaces = read_ray_spaces(src.path)
    settings = settings or Settings()
    causes = tuple(question.tell)
    missing = [c for c in causes if c not in spaces]
    if missing:
        raise ValueError(f"{src.path}: no space of the causes {missing}")
    layered = bool((skins[["t_d_mm", "t_h_mm"]] != 1.0).any().any()) or any(
        d.given for d in designs)
    on_demand = (OnDemandRays(spaces[BASELINE].spec, progress=None) if layered else None)
    rows = predict_designs(skins, designs, spaces=spaces, settings=settings, causes=causes,
                           workers=workers, on_demand=on_demand, solve_rays=solve_rays,
                           progress=progress)
    summary = summarize(rows, designs, causes, question.quantile)
    choice = recommend(summary, question)
    notes = _notes(rows, layered, solve_rays, causes)
    if any(d.protocol != "ramp" for d in designs):
        from ._predict_time import time_notes

        timed = next(d for d in designs if d.protocol != "ramp")
        notes += time_notes(timed, "Mode 1 and mode 2 designs")
    header = (f"{len(skins)} skins ({source}), {len(designs)} designs; "
              f"space: {src.info()['description']}.")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = {"predictions": out / "predictions.csv", "designs": out / "designs.csv",
             "markdown": out / "design.md", "record": out / "design.json"}
    write_table(rows, paths["predictions"])
    write_table(summary, paths["designs"])
    with atomic_output(paths["markdown"]) as tmp:
        tmp.write_text(design_markdown(summary, question, choice, causes, notes, header))
    record = {"question": {"precision": question.precision, "tell": list(question.tell),
                           "quantile": question.quantile, "rate": question.rate},
              "recommendation": choice, "skins": len(skins), "source": source, "seed": seed,
              "designs": [d.__dict__ for d in designs], "space": str(src.path),
              "space_description": src.info()["description"], "solve_rays": solve_rays,
              "settings": settings.__dict__, "version": __version__,
              "created_utc": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
              "seconds": time.perf_counter() - t0}
    with atomic_output(paths["record"]) as tmp:
        tmp.write_text(json.dumps(record, indent=2, default=str) + "\n")
    if figures:
        from skinsuction.figures.design import plot_design_precision

        paths["figure"] = plot_design_precision(summary, question, out / "precision.png")
    return {"recommendation": choice, "summary": summary, "rows": rows, "notes": notes,
            "paths": {k: str(v) for k, v in paths.items()},
            "seconds": time.perf_counter() - t0}


def _notes(rows, layered, solve_rays, causes) -> list:
    """What the user must know: skins beyond the space, approximations, errors."""
    notes = []
    beyond = rows[rows["beyond_space"].fillna(False).astype(bool)]
    if len(beyond):
        per = beyond.groupby("design").size()
        where = ", ".join(f"{n} skins with {d}" for d, n in per.items())
        notes.append("BEYOND THE SPACE: the ramp leaves the simulated space (p/X1d above its "
                     f"load range, or the rays stop before its top) for {where}; counted as "
                     "open (no interval).")
    if layered and causes and not solve_rays:
        notes.append("At layers given or other than 1 mm the causes' effects are carried over "
                     "from the 1 mm layers they were simulated for (an approximation away "
                     "from 1 mm, docs/geometry.md); --solve-rays solves them at each skin's "
                     "layers.")
    if layered:
        notes.append("Layers given or other than 1 mm: the neo-Hookean curves are read off "
                     "the geometry space (rays solved on demand where it cannot answer); a "
                     "given thickness's sd is a nuisance parameter of every interval.")
    err = rows[rows["error"].notna()]
    if len(err):
        notes.append(f"{len(err)} predictions failed (see predictions.csv, column error): "
                     f"first: {err['error'].iloc[0]}")
    for c in causes:
        if f"{c}_error" in rows:
            e = rows[rows[f"{c}_error"].notna()]
            if len(e):
                notes.append(f"{c}: not predicted for {len(e)} skin-design pairs, counted as "
                             f"not detectable (column {c}_error; first: {e[f'{c}_error'].iloc[0]})")
    return notes
