"""A design's predictions against what happens: FE virtual experiments, diagnosed.

For one skin of the box and one design, :func:`check_skin` predicts (the spaces,
noise-free: :func:`~skinsuction.design.predict_skin`) and then measures the same skin:
FE curves of the neo-Hookean skin and of the skin with each cause added (the FE model
with its fallback meshes, not the spaces' rays), noisy, read at the device's step, with
the given thicknesses in the file's header as a user writes them, and diagnosed as a
user runs ``diagnose`` (the noise estimated from the curves).  :func:`check_summary`
sets the realised beside the predicted over many skins.  ``benchmarks/design_check.py``
runs it in processes, the workflow's ``design_check`` one job a skin.
"""

from __future__ import annotations

import math
import tempfile
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from ._box import CAUSE_COLUMNS, designs_from, relative_halfwidth
from ._predict import predict_skin

CHECK_CAUSES = ("pre_tension", "hypodermis_thickness", "strain_stiffening")
#: the given thicknesses' header keys of a measured CSV
_HEADER = {"t_d": "dermis_thickness", "t_h": "hypodermis_thickness"}
_LAYER = {"t_d": "t_d_mm", "t_h": "t_h_mm"}


def parse_design(text: str, *, noise_um=2.0, resolution_mm=0.01, given=None):
    """``"2+4+8@300"`` -> that :class:`~skinsuction.design.Design` (100 mbar if no ``@``).

    >>> parse_design("2+4+8@300", given={"t_d": 0.1}).name
    '2+4+8 mm, 300 mbar, t_d given'
    """
    probes, _, mbar = str(text).partition("@")
    return designs_from([probes], [float(mbar or 100)], noise_um=noise_um,
                        resolution_mm=resolution_mm, given=given)[0]


def measure_skin(skin: dict, design, cause, seed: int, folder) -> Path | None:
    """FE curves of ``skin`` (with ``cause`` added) as ``design`` measures them: noisy,
    read at its resolution, the given thicknesses (their true values) and sd in the
    header.  None where the FE model finds no equilibrium before the ramp's top."""
    from skinsuction.evaluation import virtual_experiment, write_csv
    from skinsuction.space import default_registry

    x1d = float(skin["x1d_mpa"])
    c = default_registry()[cause] if cause else None
    value = None if c is None else c.value(float(skin[CAUSE_COLUMNS[cause]]), x1d)
    layers = {"t_d": float(skin.get("t_d_mm", 1.0)), "t_h": float(skin.get("t_h_mm", 1.0))}
    ve = virtual_experiment(x1d, x1d * float(skin["x1h_ratio"]), c, value,
                            noise_um=design.noise_um, seed=seed, probes_mm=design.probes_mm,
                            pressures_mbar=np.linspace(0.0, design.max_mbar, design.points),
                            layers=layers,
                            fallback=[{"element": "quad9", "quadrature": "full",
                                       "wall_penalty": 1.0, "iterations_per_step": 30}])
    if not ve.converged:
        return None
    step = design.resolution_mm
    if step:
        ve.curves = {k: np.round(m / step) * step for k, m in ve.curves.items()}
    header = []
    for key, sd in design.given.items():
        header += [f"{_HEADER[key]}_mm: {layers[key]:g}", f"{_HEADER[key]}_sd_mm: {sd:g}"]
    return write_csv(ve, Path(folder) / f"{cause or 'none'}_{seed}.csv", header=header)


def _realised_intervals(row: dict, result: dict, skin: dict) -> None:
    truth = {"X1d": float(skin["x1d_mpa"]),
             "X1h": float(skin["x1d_mpa"]) * float(skin["x1h_ratio"])}
    for k, v in truth.items():
        iv = (result["baseline"]["intervals"] or {}).get(k)
        est = result["baseline"]["parameters"][k]
        ns = None if iv is None else SimpleNamespace(**iv)
        row[f"real_{k}_halfwidth"], row[f"real_{k}_bounded"] = relative_halfwidth(k, est, ns)
        row[f"real_{k}_covers"] = None if ns is None else bool(ns.lower <= v <= ns.upper)


def check_skin(skin: dict, design, seed: int, spaces: dict, settings, *,
               causes=CHECK_CAUSES, pairs=None, on_demand=False) -> dict:
    """One skin, one design: the prediction and the diagnoses of its FE measurements.

    Returns one row: the skin's columns, ``pred_*`` (:func:`predict_skin`'s row) and per
    measurement (``none`` and each cause) ``real_<m>_verdict``, ``_cause``, ``_tied``,
    ``_cpu_s`` (or ``_error``); the realised X1d and X1h half-widths, bounded and
    covering flags of the neo-Hookean skin's diagnosis.  The predictions weigh every
    cause of ``spaces`` as a rival, as the diagnosis does.  ``on_demand`` is passed to
    the diagnosis (None: read the given layers' rays off the geometry space).
    """
    from skinsuction.diagnose import diagnose_file

    row = {"design": design.name, "skin": int(skin["skin"]), "seed": int(seed), **skin}
    t0 = time.process_time()
    pred = predict_skin(skin, design, spaces, settings, causes=causes,
                        on_demand=_predict_rays(design, spaces, on_demand))
    row["predict_cpu_s"] = time.process_time() - t0
    row.update({f"pred_{k}": v for k, v in pred.items() if k not in ("design", "skin")})
    with tempfile.TemporaryDirectory() as folder:
        for cause in (None, *causes):
            name = cause or "none"
            path = measure_skin(skin, design, cause, seed, folder)
            if path is None:
                row[f"real_{name}_error"] = "FE curve stopped"
                continue
            t0 = time.process_time()
            try:
                r = diagnose_file(path, None, settings, spaces=spaces, pairs=pairs,
                                  on_demand=on_demand)
            except Exception as err:  # the row records it; the other measurements go on
                row[f"real_{name}_error"] = f"{type(err).__name__}: {' '.join(str(err).split())}"
                continue
            row[f"real_{name}_cpu_s"] = time.process_time() - t0
            row[f"real_{name}_verdict"] = r["verdict"]
            row[f"real_{name}_cause"] = r["cause"]
            row[f"real_{name}_tied"] = ";".join(r["ambiguous_with"] or [])
            if cause is None:
                _realised_intervals(row, r, skin)
    return row


def repredict(row: dict, design, spaces: dict, settings, *, causes=CHECK_CAUSES,
              on_demand=False) -> dict:
    """A row of :func:`check_skin` with its prediction made again, its measurements kept.

    When only the prediction changed, its FE virtual experiments and diagnoses (the
    ``real_*`` columns: the costly part, seeded) stand; the skin is the row's own
    columns.

    >>> from skinsuction.space import SHIPPED_SPACE_DIR, read_ray_spaces
    >>> row = {"skin": 0, "x1d_mpa": 0.005, "x1h_ratio": 0.1, "pred_X1d_halfwidth": 9.0,
    ...        "real_X1d_halfwidth": 0.01}
    >>> new = repredict(row, parse_design("2@500"), read_ray_spaces(SHIPPED_SPACE_DIR),
    ...                 None, causes=())
    >>> new["pred_beyond_space"], "pred_X1d_halfwidth" in new, new["real_X1d_halfwidth"]
    (True, False, 0.01)
    """
    skin = {k: v for k, v in row.items() if not k.startswith(("pred_", "real_"))
            and k not in ("design", "seed", "predict_cpu_s")}
    out = {k: v for k, v in row.items() if not k.startswith("pred_")}
    t0 = time.process_time()
    pred = predict_skin(skin, design, spaces, settings, causes=causes,
                        on_demand=_predict_rays(design, spaces, on_demand))
    out["predict_cpu_s"] = time.process_time() - t0
    out.update({f"pred_{k}": v for k, v in pred.items() if k not in ("design", "skin")})
    return out


def _predict_rays(design, spaces, on_demand):
    """The prediction's rays at given layers: the diagnosis's solver, or one of its own."""
    if not design.given or on_demand not in (None, True):
        return on_demand or None
    from skinsuction.space import BASELINE, OnDemandRays

    return OnDemandRays(spaces[BASELINE].spec)


def _binom(p, n) -> float:
    return math.sqrt(max(p * (1 - p), 1e-12) / max(n, 1))


def check_summary(df, causes=CHECK_CAUSES) -> list:
    """Lines of text: per design, predicted against realised (intervals, bounded
    fractions, each cause's detectability and naming rate against its ceiling)."""
    from skinsuction.evaluation import attribution_ceiling

    lines = []
    for design, g in df.groupby("design", sort=False):
        ok = g[~g["pred_beyond_space"].fillna(False).astype(bool)]
        lines.append(f"{design}: {len(g)} skins, {len(g) - len(ok)} beyond the space")
        for k in ("X1d", "X1h"):
            if f"real_{k}_halfwidth" not in ok:
                continue
            pw, rw = ok[f"pred_{k}_halfwidth"].astype(float), ok[f"real_{k}_halfwidth"].astype(float)
            pb = ok[f"pred_{k}_bounded"].fillna(False).astype(bool).mean()
            rb = ok[f"real_{k}_bounded"].fillna(False).astype(bool).mean()
            cov = ok[f"real_{k}_covers"].dropna().astype(bool)
            lines.append(f"  {k}: half-width median predicted {100 * pw.median():.3g} %, "
                         f"realised {100 * rw.median():.3g} %; bounded predicted {pb:.2f}, "
                         f"realised {rb:.2f} (binomial sd {_binom(pb, len(ok)):.2f}); "
                         f"realised intervals cover the truth in {cov.sum()}/{len(cov)}")
        for c in causes:
            lines += _cause_lines(ok, c, attribution_ceiling)
    return lines


def _cause_lines(ok, c, attribution_ceiling) -> list:
    if f"pred_{c}_detectable" not in ok or f"real_{c}_verdict" not in ok:
        return [f"  {c}: not predicted or not measured here"]
    pdet = ok[f"pred_{c}_detectable"].fillna(False).astype(bool)
    found = ok[f"real_{c}_verdict"] == "cause_found"
    lines = [f"  {c}: detectable predicted {pdet.mean():.2f}, a cause found realised "
             f"{found.mean():.2f} (sd {_binom(pdet.mean(), len(ok)):.2f})"]
    on = ok[pdet]
    if len(on):
        gaps = on[[col for col in on if col.startswith(f"pred_{c}_vs_")]]
        ceiling = attribution_ceiling(gaps.min(axis=1).astype(float)).mean()
        named = on[f"real_{c}_cause"] == c
        tied = on[f"real_{c}_tied"].fillna("").astype(str).str.len() > 0
        # no cause found is a miss, not a wrong cause (the confusion rates' convention)
        missed = on[f"real_{c}_verdict"] != "cause_found"
        lines.append(f"    over the {len(on)} predicted detectable: ceiling {ceiling:.2f}, "
                     f"named right {named.sum()}/{len(on)} = {named.mean():.2f} "
                     f"(sd {_binom(ceiling, len(on)):.2f}); right or tied "
                     f"{(named | tied).mean():.2f}, wrong and not tied "
                     f"{(~named & ~tied & ~missed).sum()}/{len(on)}, no cause found "
                     f"{missed.sum()}/{len(on)}")
    return lines
