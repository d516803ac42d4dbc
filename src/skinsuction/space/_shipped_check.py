"""Does a fresh build of the scale-free space agree with the one shipped with skinsuction?

The shipped space (:mod:`._shipped`) is only as good as its agreement with the
code: the workflow's ``check_shipped_space`` rule compares a fresh build with
it ray by ray (:func:`compare_ray_spaces`, :func:`check_shipped_space`), when
the configuration is the one it was built from (:func:`shipped_check_applies`),
and ``tests/test_shipped_space.py`` re-solves a few of its rays on every push.
A ray whose end depends on the solver's path (:func:`knife_edge_rays`) may move
with round-off and is only logged.
"""

from __future__ import annotations

import logging
import math
from pathlib import Path

import numpy as np
import pandas as pd

from skinsuction._files import write_table

from ._causes import BASELINE
from ._ray_space import RaySpace, read_ray_space
from ._rays import rays_of
from ._shipped import PROVENANCE_FILE, SHIPPED_SPACE_DIR, _normal, shipped_provenance, verify_shipped_files

log = logging.getLogger(__name__)

__all__ = ["shipped_check_applies", "compare_ray_spaces", "knife_edge_rays",
           "check_shipped_space", "check_shipped_sample", "sample_bundles",
           "ShippedSpaceMismatch", "SHIPPED_RTOL", "SHIPPED_ATOL_MM"]

#: Tolerance of :func:`compare_ray_spaces`: |built - shipped| <= RTOL |shipped| + ATOL.
SHIPPED_RTOL = 1e-9
SHIPPED_ATOL_MM = 1e-12

#: Fields of a cause that change its rays (not its wording): what must agree for
#: a fresh build to be comparable with the shipped space.
_CAUSE_KEYS = ("keyword", "modulus", "neutral", "nodes", "scale")


def _cause_keys(causes: dict) -> dict:
    out = {}
    for name, c in (causes or {}).items():
        d = c.to_dict() if hasattr(c, "to_dict") else dict(c)
        out[name] = {k: d.get(k) for k in _CAUSE_KEYS}
    return _normal(out)


def _differing_keys(a, b, prefix="") -> list:
    if isinstance(a, dict) and isinstance(b, dict):
        keys = []
        for k in sorted(set(a) | set(b)):
            keys += _differing_keys(a.get(k), b.get(k), f"{prefix}{k}.")
        return keys
    return [] if a == b else [prefix.rstrip(".")]


def shipped_check_applies(spec, causes: dict, provenance: dict | None) -> tuple:
    """Whether a build of ``spec`` and ``causes`` is the space that was shipped.

    It is when the effective ray specification (probes, ratio nodes, loads, X1d
    window and reference, bottom, mesh and fallbacks: what the workflow derives
    from the ``scale_free_space`` section and the study's ``mesh``) and the
    causes' rays (keyword, modulus, neutral, nodes, scale; not their wording)
    equal those recorded in ``PROVENANCE.json``.

    Parameters
    ----------
    spec : RaySpec or dict
        The build's ray specification.
    causes : dict
        ``{name: Cause or its dict}`` of the build.
    provenance : dict or None
        The shipped space's ``PROVENANCE.json``.

    Returns
    -------
    (bool, str)
        Whether it applies, and why (the differing keys if not).

    Examples
    --------
    >>> from skinsuction.space import RaySpec
    >>> spec = RaySpec(probes_mm=[2, 6], ratio_nodes=[0.01, 0.1], load_max=100)
    >>> shipped_check_applies(spec, {}, {"ray_spec": spec.to_dict(), "causes": {}})
    (True, 'the configuration is the one the shipped space was built from')
    >>> ok, why = shipped_check_applies(spec, {}, {"ray_spec": {**spec.to_dict(), "load_max": 200},
    ...                                            "causes": {}})
    >>> ok, why.rsplit(": ", 1)[-1]
    (False, 'ray_spec.load_max')
    """
    if not provenance:
        return False, "no shipped space (no PROVENANCE.json)"
    spec_d = _normal(spec.to_dict() if hasattr(spec, "to_dict") else spec)
    keys = _differing_keys({"ray_spec": spec_d, "causes": _cause_keys(causes)},
                           {"ray_spec": _normal(provenance.get("ray_spec") or {}),
                            "causes": _cause_keys(provenance.get("causes") or {})})
    if keys:
        shown = ", ".join(keys[:8]) + (f" and {len(keys) - 8} more" if len(keys) > 8 else "")
        return False, ("the configuration's scale-free space differs from the one the shipped "
                       f"space was built from ({provenance.get('config_file') or 'a custom configuration'}): "
                       f"{shown}")
    return True, "the configuration is the one the shipped space was built from"


# ----------------------------------------------------------- ray-by-ray comparison
def _ray_arrays(space: RaySpace) -> dict:
    """``{ray_id: deflections}`` of a space, with its probe/ratio/coordinate axes checked."""
    out = {}
    for ray in rays_of(space.spec, space.cause):
        if not space.has_probe(ray["probe_mm"]):
            continue
        i = space.spec.ratio_nodes.index(ray["ratio"])
        j = 0 if space.cause is None else list(space.coordinates).index(ray["coordinate"])
        out[ray["ray_id"]] = space.rays(ray["probe_mm"])[i, j]
    return out


def compare_ray_spaces(built: RaySpace, shipped: RaySpace, rtol: float = SHIPPED_RTOL,
                       atol: float = SHIPPED_ATOL_MM, ray_ids=None) -> tuple:
    """Compare two spaces of one model ray by ray: ``(row, {ray_id: why})``.

    A ray agrees when both spaces hold it (same id: probe, X1h/X1d, cause
    coordinate), at the same pressures, with the same NaN pattern, and
    ``|built - shipped| <= rtol |shipped| + atol`` (mm) at every finite node.

    Parameters
    ----------
    built, shipped : RaySpace
        The two spaces of one model.
    rtol : float
        Relative tolerance.
    atol : float
        Absolute tolerance (mm).
    ray_ids : collection of str, optional
        Compare these rays only (a sample solved afresh); default every ray.

    Returns
    -------
    row : dict
        ``model, rays_compared, rays_differing, max_abs_diff_mm, max_rel_diff``
        (largest differences over the rays both hold).
    bad : dict
        ``{ray_id: why}`` of the rays that differ.

    Examples
    --------
    >>> import numpy as np
    >>> from skinsuction.space import RaySpace, RaySpec
    >>> spec = RaySpec(probes_mm=[2], ratio_nodes=[0.01, 0.1], load_max=100, load_steps=3)
    >>> a = RaySpace(None, spec, np.array([np.nan]), {2.0: np.ones((2, 1, 4))})
    >>> b = RaySpace(None, spec, np.array([np.nan]), {2.0: np.ones((2, 1, 4))})
    >>> b.deflection_mm[2.0][1, 0, 3] = np.nan
    >>> row, bad = compare_ray_spaces(a, b)
    >>> row["rays_compared"], row["rays_differing"], list(bad.values())
    (2, 1, ['NaN pattern differs: 1 nodes, the first at p/X1d = 100, NaN in the shipped space'])
    """
    name = shipped.name
    rows = {"model": name, "rays_compared": 0, "rays_differing": 0,
            "max_abs_diff_mm": 0.0, "max_rel_diff": 0.0}
    bad = {}
    if built.name != name:
        raise ValueError(f"comparing the {built.name} space with the {name} space")
    loads_b, loads_s = built.spec.load_nodes, shipped.spec.load_nodes
    same_p = loads_b.shape == loads_s.shape and np.allclose(loads_b, loads_s, rtol=1e-12)
    rb, rs = _ray_arrays(built), _ray_arrays(shipped)
    if ray_ids is not None:
        rb = {k: v for k, v in rb.items() if k in ray_ids}
        rs = {k: v for k, v in rs.items() if k in ray_ids}
    for rid in sorted(set(rs) - set(rb)):
        bad[rid] = "in the shipped space, not in the build"
    for rid in sorted(set(rb) - set(rs)):
        bad[rid] = "in the build, not in the shipped space"
    for rid in sorted(set(rb) & set(rs)):
        rows["rays_compared"] += 1
        a, b = rb[rid], rs[rid]
        if not same_p:
            bad[rid] = "loads p/X1d differ"
            continue
        fa, fb = np.isfinite(a), np.isfinite(b)
        both = fa & fb
        if both.any():
            d = np.abs(a[both] - b[both])
            rel = d / np.maximum(np.abs(b[both]), atol)
            rows["max_abs_diff_mm"] = max(rows["max_abs_diff_mm"], float(d.max()))
            rows["max_rel_diff"] = max(rows["max_rel_diff"], float(rel.max()))
        if not np.array_equal(fa, fb):
            k = int(np.flatnonzero(fa != fb)[0])
            side = "the build" if fb[k] else "the shipped space"
            bad[rid] = (f"NaN pattern differs: {int((fa != fb).sum())} nodes, the first at "
                        f"p/X1d = {loads_b[k]:.4g}, NaN in {side}")
        elif both.any() and not np.all(np.abs(a[both] - b[both]) <= rtol * np.abs(b[both]) + atol):
            d = np.abs(a[both] - b[both])
            k = int(np.argmax(d - rtol * np.abs(b[both])))
            bad[rid] = (f"deflections differ: largest {float(d.max()):.3g} mm "
                        f"(relative {float((d / np.maximum(np.abs(b[both]), atol)).max()):.3g}; "
                        f"at p/X1d = {loads_b[both][k]:.4g})")
    rows["rays_differing"] = len(bad)
    return rows, bad


class ShippedSpaceMismatch(RuntimeError):
    """A fresh build of the default space differs from the space shipped with skinsuction."""


def knife_edge_rays(*spaces) -> set:
    """Rays whose end depends on the solver's path, in any of ``spaces``: a fallback
    element carries part of them, or they stop before their last load.

    Where the default element stops, and so where a fallback's tail is spliced on,
    moves with round-off (the same solver on FElupe's assembly and on the fast one,
    equal to 1e-13, stops at different loads there): such a ray can differ between
    two machines while every ray the default element carries to the end agrees to
    round-off.

    Parameters
    ----------
    *spaces : RaySpace
        Spaces whose solver records (``metadata["rays"]``) are read.

    Returns
    -------
    set of str
        Ray ids.

    Examples
    --------
    >>> from types import SimpleNamespace as S
    >>> a = S(metadata={"rays": {"r1": {"mesh_fallback": 1, "converged": True},
    ...                          "r2": {"mesh_fallback": 0, "converged": True}}})
    >>> b = S(metadata={"rays": {"r2": {"mesh_fallback": 0, "converged": False}}})
    >>> sorted(knife_edge_rays(a, b))
    ['r1', 'r2']
    """
    out = set()
    for space in spaces:
        for rid, info in ((space.metadata or {}).get("rays") or {}).items():
            if int(info.get("mesh_fallback") or 0) > 0 or not info.get("converged", True):
                out.add(rid)
    return out


def check_shipped_space(built_dir, out_csv, spec, causes: dict, shipped_dir=SHIPPED_SPACE_DIR,
                        rtol: float = SHIPPED_RTOL, atol: float = SHIPPED_ATOL_MM) -> pd.DataFrame:
    """Compare the workflow's build of the scale-free space with the shipped one; write a table.

    When the configuration (``spec``, ``causes``) is the one the shipped space was
    built from (:func:`shipped_check_applies`), every model file of the shipped
    space is compared with the build's, ray by ray (:func:`compare_ray_spaces`),
    and ``out_csv`` gets one row per model: ``model, status`` (``equal``,
    ``knife_edge_moved`` or ``differs``), ``rays_compared, rays_differing,
    max_abs_diff_mm, max_rel_diff, rtol, atol_mm, differing_rays`` (the first 20
    ids), ``knife_edge_rays`` (how many of the differing rays are
    :func:`knife_edge_rays`), ``note``.  Otherwise the table has one row, status
    ``not_applicable``, saying why.

    A differing ray that a fallback carries or that stops early, in either space,
    is logged as a warning and counted (``knife_edge_moved``); any other differing
    ray fails the check.

    Parameters
    ----------
    built_dir : path-like
        The fresh build's folder.
    out_csv : path-like
        The table written.
    spec : RaySpec
        The configuration's ray specification.
    causes : dict
        ``{name: Cause}`` of the configuration.
    shipped_dir : path-like
        The shipped space (default: the package's).
    rtol, atol : float
        Tolerances of :func:`compare_ray_spaces` (relative, mm).

    Returns
    -------
    pandas.DataFrame
        The table written to ``out_csv``.

    Raises
    ------
    ShippedSpaceMismatch
        Naming the rays that differ and are not knife-edge rays (after writing the
        table and logging every differing ray), so that a workflow run fails loudly.
    """
    shipped_dir = Path(shipped_dir)
    prov = shipped_provenance(shipped_dir)
    applies, reason = shipped_check_applies(spec, causes, prov)
    if not applies:
        log.info("check of the shipped space does not apply: %s", reason)
        table = pd.DataFrame([{"model": "", "status": "not_applicable", "rays_compared": 0,
                               "rays_differing": 0, "max_abs_diff_mm": math.nan,
                               "max_rel_diff": math.nan, "rtol": rtol, "atol_mm": atol,
                               "differing_rays": "", "knife_edge_rays": 0, "note": reason}],
                             columns=_CHECK_COLUMNS)
        write_table(table, out_csv)
        return table
    problems = verify_shipped_files(shipped_dir)
    if problems:
        raise ShippedSpaceMismatch(f"{shipped_dir}: the shipped files disagree with their "
                                   f"{PROVENANCE_FILE}: " + "; ".join(problems))
    rows, all_bad = [], {}
    for name in sorted(prov["files"], key=lambda n: (n != f"{BASELINE}.parquet", n)):
        row, bad = _check_model_file(name, Path(built_dir), shipped_dir, rtol, atol)
        rows.append({**row, "note": reason})
        all_bad.update(bad)
    table = pd.DataFrame(rows, columns=_CHECK_COLUMNS)
    write_table(table, out_csv)
    log.info("shipped space check:\n%s", table.drop(columns=["note"]).to_string(index=False))
    if all_bad:
        raise ShippedSpaceMismatch(_mismatch_text(all_bad, built_dir, shipped_dir, rtol, atol))
    return table


#: Columns of the table of :func:`check_shipped_space`.
_CHECK_COLUMNS = ["model", "status", "rays_compared", "rays_differing", "max_abs_diff_mm",
                  "max_rel_diff", "rtol", "atol_mm", "differing_rays", "knife_edge_rays", "note"]


def _check_model_file(name, built_dir: Path, shipped_dir: Path, rtol, atol) -> tuple:
    """Compare one model file of the build with the shipped one (:func:`_compare_logged`)."""
    shipped = read_ray_space(shipped_dir / name)
    built_path = built_dir / name
    if not built_path.is_file():
        raise ShippedSpaceMismatch(f"{built_path}: not built, but shipped ({name})")
    return _compare_logged(name, read_ray_space(built_path), shipped, rtol, atol)


def _compare_logged(name, built, shipped, rtol, atol, ray_ids=None) -> tuple:
    """Compare a build with the shipped space of one model and log its differing rays.

    Returns its row of the table (without the note) and ``{"model: ray_id": why}``
    for the differing rays that are not knife-edge rays."""
    row, bad = compare_ray_spaces(built, shipped, rtol, atol, ray_ids)
    ids = sorted(bad)
    edge = knife_edge_rays(built, shipped) & set(ids)
    status = "equal" if not bad else ("knife_edge_moved" if edge == set(ids) else "differs")
    row = {**row, "status": status, "rtol": rtol, "atol_mm": atol,
           "differing_rays": ";".join(ids[:20]) + (f";... {len(ids) - 20} more"
                                                   if len(ids) > 20 else ""),
           "knife_edge_rays": len(edge)}
    for rid in ids:
        if rid in edge:
            log.warning("%s: ray %s (a fallback carries it or it stops early: where, "
                        "moves with round-off): %s", name, rid, bad[rid])
        else:
            log.error("%s: ray %s: %s", name, rid, bad[rid])
    log.info("%s: %d rays compared, %d differ (largest difference %.3g mm, relative %.3g)",
             name, row["rays_compared"], row["rays_differing"], row["max_abs_diff_mm"],
             row["max_rel_diff"])
    return row, {f"{shipped.name}: {rid}": why for rid, why in bad.items() if rid not in edge}


# ------------------------------------------------- the study on the shipped space
def sample_bundles(bundles, k: int, seed: int) -> list:
    """``k`` of the ray bundles' ids, drawn without replacement (seeded), sorted.

    >>> sample_bundles(["a", "b", "c", "d"], 2, 0) == sample_bundles(["d", "c", "b", "a"], 2, 0)
    True
    >>> len(sample_bundles(["a", "b"], 5, 0))
    2
    """
    ids = sorted(bundles)
    rng = np.random.default_rng(seed)
    return sorted(rng.choice(ids, size=min(int(k), len(ids)), replace=False).tolist())


def check_shipped_sample(bundle_paths, out_csv, spec, causes: dict,
                         shipped_dir=SHIPPED_SPACE_DIR, rtol: float = SHIPPED_RTOL,
                         atol: float = SHIPPED_ATOL_MM) -> pd.DataFrame:
    """The shipped space against a sample of its rays solved afresh; write a table.

    A study that reads the shipped space instead of building it
    (``scale_free_space.source: shipped``) checks it here: the rays of
    ``bundle_paths`` (bundle files the workflow solved with the current FE code,
    named ``<model>__...``) against the same rays of the shipped files, as
    :func:`check_shipped_space` compares a whole build (one row per model,
    knife-edge rays logged, not failed).

    Raises
    ------
    ShippedSpaceMismatch
        The configuration is not the one the shipped space was built from, its
        files disagree with their provenance, or a sampled ray differs.
    """
    shipped_dir = Path(shipped_dir)
    prov = shipped_provenance(shipped_dir)
    applies, reason = shipped_check_applies(spec, causes, prov)
    if not applies:
        raise ShippedSpaceMismatch(f"the study reads the shipped space, but {reason}; build "
                                   "it instead (scale_free_space.source: build)")
    problems = verify_shipped_files(shipped_dir)
    if problems:
        raise ShippedSpaceMismatch(f"{shipped_dir}: the shipped files disagree with their "
                                   f"{PROVENANCE_FILE}: " + "; ".join(problems))
    by_model = {}
    for path in map(Path, bundle_paths):
        by_model.setdefault(path.name.split("__")[0], []).append(path)
    rows, all_bad = [], {}
    for model, paths in sorted(by_model.items(), key=lambda kv: (kv[0] != BASELINE, kv[0])):
        built = _sampled_space(paths, spec, None if model == BASELINE else causes[model])
        ids = set((built.metadata or {}).get("rays") or {})
        row, bad = _compare_logged(f"{model}.parquet", built,
                                   read_ray_space(shipped_dir / f"{model}.parquet"), rtol, atol,
                                   ray_ids=ids)
        rows.append({**row, "note": f"a sample: {len(paths)} ray bundles solved afresh"})
        all_bad.update(bad)
    table = pd.DataFrame(rows, columns=_CHECK_COLUMNS)
    write_table(table, out_csv)
    log.info("shipped space, sampled:\n%s", table.drop(columns=["note"]).to_string(index=False))
    if all_bad:
        where = f"{Path(bundle_paths[0]).parent} (a sample)"
        raise ShippedSpaceMismatch(_mismatch_text(all_bad, where, shipped_dir, rtol, atol))
    return table


def _sampled_space(paths, spec, cause) -> RaySpace:
    """The rays of some bundle files as a space of one model (the others NaN)."""
    from ._ray_space import fill_rays

    ids = set()
    for path in paths:
        ids |= set(pd.read_parquet(path, columns=["ray_id"])["ray_id"])
    rays = [r for r in rays_of(spec, cause) if r["ray_id"] in ids]
    coords = np.array(cause.nodes if cause is not None else [math.nan])
    arrays = {q: np.full((len(spec.ratio_nodes), coords.size, len(spec.pressures_mbar)), np.nan)
              for q in spec.probes_mm}
    info = fill_rays(paths, rays, arrays, spec, cause.name if cause else BASELINE,
                     lambda ray: 0 if cause is None else cause.nodes.index(ray["coordinate"]))
    return RaySpace(cause, spec, coords, arrays, {"rays": info})


def _mismatch_text(bad: dict, built_dir, shipped_dir, rtol, atol) -> str:
    """The error of a check that failed: how many rays, the first ten, the remedy."""
    shown = "; ".join(f"{rid} ({why})" for rid, why in list(bad.items())[:10])
    more = f"; and {len(bad) - 10} more (see the log)" if len(bad) > 10 else ""
    return (f"the fresh build in {built_dir} differs from the default space shipped with "
            f"skinsuction ({shipped_dir}) in {len(bad)} rays the default element carries to "
            f"the end (tolerance {rtol:g} relative + {atol:g} mm): {shown}{more}. If the FE "
            "code changed on purpose, ship the new build: `snakemake --cores 2 "
            "ship_scale_free_space`")
