"""The inputs of the paper's identification study: test curves, spaces, objectives.

The test point of the paper (section 3.2, X1d = 0.0055 MPa, X1h = 0.00041 MPa)
lives in the configuration (``identification.target``) and is passed in.  The
curve to identify comes in two variants (:data:`SOURCES`): ``fe``, a direct FE
run at the test point (honest: the point is off the grid), and ``space``, the
curve taken from the interpolated space (the paper's variant).
"""

from __future__ import annotations

import logging
import zlib
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

log = logging.getLogger(__name__)

from skinsuction.identify import ratio_objective, single_objective, weighted_objective
from skinsuction.space import GriddedSpace, evaluate

#: Variants of the curve to identify.
SOURCES = {
    "fe": "direct FE run at the test point (honest test)",
    "space": "curve taken from the interpolated space (paper's variant)",
}

#: Objectives by name: probe(s) used and the paper's equation.
OBJECTIVES = {
    "single_6mm": "6 mm probe alone (eq. 4)",
    "single_2mm": "2 mm probe alone (eq. 4)",
    "weighted": "weighted 2 mm + 6 mm (eq. 10)",
    "ratio": "ratio 6 mm / 2 mm (eqs. 11-12)",
}

#: Section 3.3.1: iterations and seconds per identification reported by the paper.
PAPER_TIMING = {"ratio": (10, 1.2), "weighted": (20, 3.8)}

#: Window focusing settings of the paper (section 2.4).
PAPER_WINDOW_FOCUSING = {"n_samples": 1000, "n_best": 20, "tolerance": 1e-6, "max_iter": 200}



def load_spaces(space_path, probes=(2.0, 6.0), bottom="fixed") -> dict:
    """The gridded spaces of ``probes`` from a simulated-space database."""
    from skinsuction.space import read_space

    space = read_space(space_path)
    return {float(p): GriddedSpace.from_space(space, float(p), bottom=bottom) for p in probes}


def make_test_curves(space_path, fe_curve_paths, out_csv=None, *, target,
                     bottom="fixed") -> pd.DataFrame:
    """The curves to identify: FE at the test point and the interpolated space there.

    Parameters
    ----------
    space_path : path-like
        Simulated-space database (both probes).
    fe_curve_paths : iterable of path-like
        Curve files (:func:`skinsuction.space.write_curve`) of direct FE runs at
        the test point, one per probe, on the space's mesh and pressures.
    out_csv : path-like, optional
        Where to write the table (atomically).
    target : (float, float)
        The test point (X1d, X1h), MPa.

    Returns
    -------
    DataFrame
        Columns ``source, probe_mm, x1d, x1h, pressure_mbar, deflection_mm``;
        only finite deflections (a non-converged FE curve keeps its converged
        part, with a warning in the log).
    """
    from skinsuction.space import read_curves
    from skinsuction._files import write_table

    frame, _ = read_curves(fe_curve_paths)
    target = np.asarray(target, dtype=float)
    rows = []
    for pid, g in frame.groupby("point_id", sort=False):
        first = g.iloc[0]
        point = np.array([first["x1d"], first["x1h"]], dtype=float)
        if not np.allclose(point, target, rtol=1e-9, atol=0):
            raise ValueError(f"FE curve {pid} is not at the test point {target.tolist()}")
        if not bool(first["converged"]):
            log.warning("FE test curve %s stopped at %s mbar (%s); its converged part is used",
                        pid, first["last_converged_mbar"], first["reason"])
        ok = g[np.isfinite(g["deflection_mm"].to_numpy(float))]
        rows.append(pd.DataFrame({
            "source": "fe", "probe_mm": float(first["probe_mm"]),
            "x1d": target[0], "x1h": target[1],
            "pressure_mbar": ok["pressure_mbar"].to_numpy(float),
            "deflection_mm": ok["deflection_mm"].to_numpy(float),
        }))
    probes = sorted({float(r["probe_mm"].iloc[0]) for r in rows})
    spaces = load_spaces(space_path, probes, bottom)
    for probe in probes:
        s = spaces[probe]
        m = evaluate(s, [target])[0]
        ok = np.isfinite(m)
        if not ok.any():
            raise ValueError(
                f"the {probe:g} mm space cannot be interpolated at the test point "
                f"{target.tolist()} (a node of its stencil did not converge)"
            )
        rows.append(pd.DataFrame({
            "source": "space", "probe_mm": probe, "x1d": target[0], "x1h": target[1],
            "pressure_mbar": s.pressure_mbar[ok], "deflection_mm": m[ok],
        }))
    table = pd.concat(rows, ignore_index=True).sort_values(
        ["source", "probe_mm", "pressure_mbar"], kind="stable").reset_index(drop=True)
    for (source, probe), g in table.groupby(["source", "probe_mm"]):
        log.info("test curve %s %g mm: %d points, M(%g mbar) = %.6f mm", source, probe,
                 len(g), g["pressure_mbar"].iloc[-1], g["deflection_mm"].iloc[-1])
    if out_csv is not None:
        write_table(table, out_csv)
    return table


def read_test_curves(path_or_frame) -> dict:
    """``{source: {probe_mm: (pressure_mbar, deflection_mm)}}`` from the test-curve table."""
    table = path_or_frame if isinstance(path_or_frame, pd.DataFrame) else pd.read_csv(path_or_frame)
    out = {}
    for (source, probe), g in table.groupby(["source", "probe_mm"], sort=True):
        g = g.sort_values("pressure_mbar")
        out.setdefault(str(source), {})[float(probe)] = (
            g["pressure_mbar"].to_numpy(float), g["deflection_mm"].to_numpy(float))
    return out


@dataclass
class StudySetup:
    """Spaces and curves of a study.

    Attributes
    ----------
    spaces : dict
        ``{probe_mm: GriddedSpace}`` for the 2 and 6 mm probes.
    curves : dict
        ``{source: {probe_mm: (pressure_mbar, deflection_mm)}}``.
    target : ndarray (2,)
        The truth (X1d, X1h), MPa.
    window_focusing : dict
        Options of :func:`skinsuction.identify.window_focusing` (N, Nb, C, max_iter).
    """

    spaces: dict
    curves: dict
    target: np.ndarray
    window_focusing: dict = field(default_factory=lambda: dict(PAPER_WINDOW_FOCUSING))

    def __post_init__(self):
        self.target = np.asarray(self.target, dtype=float)

    @property
    def sources(self) -> list:
        return list(self.curves)


def load_setup(space_path, test_curves_path, *, target, bottom="fixed",
               window_focusing=None) -> StudySetup:
    """A :class:`StudySetup` from the workflow's files."""
    curves = read_test_curves(test_curves_path)
    probes = sorted({p for c in curves.values() for p in c})
    return StudySetup(
        spaces=load_spaces(space_path, probes, bottom),
        curves=curves,
        target=np.asarray(target, dtype=float),
        window_focusing={**PAPER_WINDOW_FOCUSING, **(window_focusing or {})},
    )


def build_objective(setup: StudySetup, kind: str, source: str, alpha: float = 0.5):
    """The objective ``kind`` (see :data:`OBJECTIVES`) for the curves of ``source``."""
    s, c = setup.spaces, setup.curves[source]
    if kind == "single_6mm":
        return single_objective(s[6.0], c[6.0])
    if kind == "single_2mm":
        return single_objective(s[2.0], c[2.0])
    if kind == "weighted":
        return weighted_objective(s[2.0], c[2.0], s[6.0], c[6.0], alpha=alpha)
    if kind == "ratio":
        return ratio_objective(s[2.0], c[2.0], s[6.0], c[6.0])
    raise ValueError(f"unknown objective {kind!r}; choose among {list(OBJECTIVES)}")


def case_seed(seed: int, *labels) -> np.random.SeedSequence:
    """Independent, reproducible seed of one study case (named by ``labels``).

    >>> a = case_seed(0, "fe", "single_6mm").generate_state(1)
    >>> b = case_seed(0, "fe", "single_2mm").generate_state(1)
    >>> bool(a[0] != b[0])
    True
    """
    key = "/".join(str(x) for x in labels)
    return np.random.SeedSequence([int(seed), zlib.crc32(key.encode())])


def target_of(settings: dict) -> tuple:
    """The test point (X1d, X1h) in MPa of ``config["identification"]``: its one home."""
    try:
        t = settings["target"]
        return float(t["x1d"]), float(t["x1h"])
    except (KeyError, TypeError):
        raise ValueError("identification.target: the test point {x1d, x1h} (MPa) is "
                         "missing from the configuration") from None


def setup_from_files(space_path, test_curves_path, settings: dict) -> StudySetup:
    """A :class:`StudySetup` from the workflow's files and ``config["identification"]``."""
    return load_setup(space_path, test_curves_path, target=target_of(settings),
                      bottom=settings.get("bottom", "fixed"),
                      window_focusing=settings.get("window_focusing"))


def scale_free_setup(space_dir, test_curves_path, *, target, bottom="fixed",
                     window_focusing=None, sources=("fe",)) -> StudySetup:
    """A :class:`StudySetup` on the scale-free space (its neo-Hookean rays).

    Only the ``sources`` of the test curves are kept: the curve taken from the
    paper grid's interpolant is not a test of another space.
    """
    from skinsuction.space import NeoHookeanSlice, read_ray_spaces

    base = read_ray_spaces(space_dir)["neo_hookean"]
    if base.spec.bottom != bottom:
        raise ValueError(f"{space_dir}: the scale-free space has bottom {base.spec.bottom!r}, "
                         f"not {bottom!r}")
    curves = {k: v for k, v in read_test_curves(test_curves_path).items() if k in sources}
    return StudySetup(spaces={p: NeoHookeanSlice(base, p) for p in base.probes_mm},
                      curves=curves, target=np.asarray(target, dtype=float),
                      window_focusing={**PAPER_WINDOW_FOCUSING, **(window_focusing or {})})
