"""A SYNTHETIC clinical study of subjects with their own layers (not measurements).

Each subject has its own dermis and hypodermis, drawn over the physiological range
and *given* as an ultrasound would give them: the true thickness plus an error of the
stated sd (0.1 mm).  Each is measured twice, both FE virtual experiments at its own
layers: a ramp (2 and 6 mm probes, 0-100 mbar in 2 mbar steps, Gaussian noise of
1-3 µm) and a Cutometer mode-1 time curve (2 mm probe, 2 cycles of 3 s on / 2 s off,
sampled at 100 Hz, noise 3 µm, rounded to the Cutometer's 0.01 mm) of a skin that
creeps (a two-term spectrum shared by both layers).  The treated half of the
subjects has a dermis 25 % stiffer (the hidden group effect, cross-sectional).

The truth goes to a CSV of its own, never into the study's files, whose
``# key: value`` lines carry only what a study records: the ids (subject, group,
measurement) and the given layers with their sd.  :func:`layers_study_check`
compares what ``skinsuction study`` found with it: the coverage of the 95 %
intervals, the verdicts, and the group comparison on the estimates against the same
comparison on the true moduli.

Every draw comes from ``numpy.random.default_rng([seed, subject index])``, so a
subject's files do not depend on how many processes made them.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

__all__ = ["LayersStudyDesign", "draw_layers_subject", "make_layers_study",
           "layers_study_check", "layers_study_markdown"]

RAMP, MODE1 = "ramp", "mode 1"


@dataclass(frozen=True)
class LayersStudyDesign:
    """What the synthetic study draws (moduli in MPa, lengths in mm, times in s).

    X1d per subject is log-normal (median 0.02 MPa, log-sd 0.45, clipped to
    0.008-0.08 MPa: forearm suction E = 129 ± 88 kPa, X1d = E/6), times
    ``effect`` in the treated group; X1h/X1d log-uniform; t_d uniform and t_h
    log-uniform over the issue's physiological ranges.  The mode-1 suction (150
    mbar) keeps p/X1d within the default space's reach (20 000 mbar/MPa) at the
    softest dermis: the Cutometer's usual 450 mbar is beyond it.
    """

    subjects: int = 200
    seed: int = 2027
    effect: float = 1.25
    x1d_median: float = 0.02
    x1d_log_sd: float = 0.45
    x1d_clip: tuple = (0.008, 0.08)
    ratio_range: tuple = (0.01, 0.1)
    t_d_range: tuple = (0.5, 2.5)
    t_h_range: tuple = (0.5, 10.0)
    thickness_sd: float = 0.1
    noise_um: tuple = (1.0, 3.0)
    ramp_probes: tuple = (2.0, 6.0)
    ramp_max_mbar: float = 100.0
    mode1_probe: float = 2.0
    mode1_mbar: float = 150.0
    mode1_on_off_cycles: tuple = (3.0, 2.0, 2)
    mode1_noise_um: float = 3.0
    g_ranges: tuple = ((0.2, 0.6), (0.3, 1.0))
    tau_ranges: tuple = ((0.03, 0.1), (1.0, 3.0))
    mesh: dict = field(default_factory=dict)
    #: further solves where the first stops (as the space's rays)
    fallback: list = field(default_factory=lambda: [
        {"element": "quad9", "quadrature": "full", "wall_penalty": 1.0,
         "iterations_per_step": 30}])
    max_draws: int = 10

    @classmethod
    def from_config(cls, section: dict | None) -> "LayersStudyDesign":
        """From the config's ``generate`` section (its keys are the fields)."""
        section = dict(section or {})
        unknown = sorted(set(section) - set(cls.__dataclass_fields__))
        if unknown:
            raise ValueError(f"generate: unknown keys {unknown}")
        def freeze(v):  # lists of numbers (ranges) as tuples; the fallback stays a list
            if isinstance(v, list) and not any(isinstance(x, dict) for x in v):
                return tuple(freeze(x) for x in v)
            return v
        return cls(**{k: freeze(v) for k, v in section.items()})


def _subject_id(i: int) -> str:
    return f"S{i + 1:03d}"


def draw_layers_subject(design: LayersStudyDesign, i: int, attempt: int = 0) -> dict:
    """The truth of subject ``i`` (0-based) at its ``attempt``-th draw: moduli, layers
    as they are and as given, noise, spectrum, group.

    Examples
    --------
    >>> d = draw_layers_subject(LayersStudyDesign(subjects=4), 0)
    >>> d["subject"], d["group"], 0.5 <= d["t_d_mm"] <= 2.5
    ('S001', 'treated', True)
    >>> d == draw_layers_subject(LayersStudyDesign(subjects=4), 0)
    True
    """
    rng = np.random.default_rng([design.seed, i, attempt])
    group = "treated" if i < design.subjects // 2 else "control"
    lo, hi = design.x1d_clip
    x1d = float(np.clip(design.x1d_median * math.exp(design.x1d_log_sd * rng.standard_normal()),
                        lo, hi))
    x1d *= design.effect if group == "treated" else 1.0
    ratio = math.exp(rng.uniform(*np.log(design.ratio_range)))
    t_d = float(rng.uniform(*design.t_d_range))
    t_h = float(math.exp(rng.uniform(*np.log(design.t_h_range))))
    sd = design.thickness_sd
    # an ultrasound reading: the truth plus an error of its sd, to 0.01 mm
    given_d = round(max(t_d + sd * rng.standard_normal(), 0.05), 2)
    given_h = round(max(t_h + sd * rng.standard_normal(), 0.05), 2)
    g = [float(rng.uniform(*r)) for r in design.g_ranges]
    tau = [float(math.exp(rng.uniform(*np.log(r)))) for r in design.tau_ranges]
    return {"subject": _subject_id(i), "group": group, "attempt": attempt,
            "x1d_mpa": x1d, "x1h_mpa": x1d * ratio, "t_d_mm": t_d, "t_h_mm": t_h,
            "t_d_given_mm": given_d, "t_h_given_mm": given_h, "thickness_sd_mm": sd,
            "noise_um": float(rng.uniform(*design.noise_um)),
            "g": g, "tau_s": tau, "seed": int(rng.integers(2**31))}


def _header(truth: dict, measurement: str) -> list:
    sd = truth["thickness_sd_mm"]
    return ["SYNTHETIC STUDY, NOT A MEASUREMENT (skinsuction FE model + noise; the truth "
            "is kept apart)",
            f"subject: {truth['subject']}", f"group: {truth['group']}",
            f"measurement: {measurement}",
            f"dermis_thickness_mm: {truth['t_d_given_mm']:g}", f"dermis_thickness_sd_mm: {sd:g}",
            f"hypodermis_thickness_mm: {truth['t_h_given_mm']:g}",
            f"hypodermis_thickness_sd_mm: {sd:g}"]


def _ramp(design: LayersStudyDesign, truth: dict):
    from ._virtual import virtual_experiment

    p = np.arange(0.0, design.ramp_max_mbar + 1.0, 2.0)
    ve = virtual_experiment(truth["x1d_mpa"], truth["x1h_mpa"], noise_um=truth["noise_um"],
                            seed=truth["seed"], probes_mm=design.ramp_probes, pressures_mbar=p,
                            mesh=design.mesh, fallback=list(design.fallback),
                            layers={"t_d": truth["t_d_mm"], "t_h": truth["t_h_mm"]})
    if not ve.converged:
        raise RuntimeError("the FE ramp stopped before 100 mbar")
    return p, ve


def _mode1(design: LayersStudyDesign, truth: dict):
    from skinsuction.model import Prony, Skin

    from ._time_virtual import mode1_suction, virtual_skin_curve

    on, off, cycles = design.mode1_on_off_cycles
    skin = Skin.two_layer(truth["x1d_mpa"], truth["x1h_mpa"], t_d=truth["t_d_mm"],
                          t_h=truth["t_h_mm"], spectrum=Prony(truth["g"], truth["tau_s"]))
    t, p, d, _, _ = virtual_skin_curve(
        skin, mode1_suction(design.mode1_mbar, on, off, int(cycles)),
        probe_mm=design.mode1_probe, noise_mm=1e-3 * design.mode1_noise_um,
        seed=truth["seed"] + 1, mesh=design.mesh or None)
    return t, p, d


def _write_ramp(path: Path, truth: dict, p, ve) -> None:
    from skinsuction._files import atomic_output

    lines = [f"# {h}" for h in _header(truth, RAMP)] + ["probe_mm,pressure_mbar,deflection_mm"]
    for probe in ve.probes_mm:
        lines += [f"{probe:g},{a:g},{b:.5f}" for a, b in zip(p, ve.curves[(probe, 0)])]
    with atomic_output(path) as tmp:
        tmp.write_text("\n".join(lines) + "\n", encoding="utf-8")


def _make_subject(job):
    """Draw subject ``i`` (redrawn where an FE solve stops) and write its two files."""
    from ._time_virtual import write_time_csv

    design, i, folder = job
    folder = Path(folder)
    failures = []
    for attempt in range(design.max_draws):
        truth = draw_layers_subject(design, i, attempt)
        try:
            p, ve = _ramp(design, truth)
            t, pt, d = _mode1(design, truth)
        except (RuntimeError, ValueError) as err:  # an FE solve that stopped: redraw, say so
            failures.append(f"draw {attempt}: {err}")
            continue
        ramp_file = folder / f"{truth['subject']}_ramp.csv"
        mode1_file = folder / f"{truth['subject']}_mode1.csv"
        _write_ramp(ramp_file, truth, p, ve)
        write_time_csv(mode1_file, [(design.mode1_probe, t, pt, d)],
                       header=_header(truth, MODE1))
        base = {k: v for k, v in truth.items() if k not in ("g", "tau_s")}
        spectrum = {"g_1": truth["g"][0], "tau_1_s": truth["tau_s"][0],
                    "g_2": truth["g"][1], "tau_2_s": truth["tau_s"][1]}
        return [{**base, **spectrum, "file": f.name, "measurement": m,
                 "redrawn_because": "; ".join(failures)}
                for f, m in ((ramp_file, RAMP), (mode1_file, MODE1))]
    raise RuntimeError(f"subject {_subject_id(i)}: no draw of {design.max_draws} was solved "
                       f"({'; '.join(failures)})")


def make_layers_study(folder, truth_path, design: LayersStudyDesign | None = None,
                      processes: int = 1, progress=None) -> pd.DataFrame:
    """Make the study's files in ``folder`` and its truth in ``truth_path``.

    Parameters
    ----------
    folder : path-like
        Receives ``S001_ramp.csv``, ``S001_mode1.csv``, ... and a README.
    truth_path : path-like
        The truth, one row per file (CSV, written atomically).
    design : LayersStudyDesign, optional
    processes : int
        Subjects solved in parallel (the files do not depend on it).
    progress : text stream, optional

    Returns
    -------
    pandas.DataFrame
        The truth.
    """
    from concurrent.futures import ProcessPoolExecutor

    from skinsuction._files import atomic_output

    design = design or LayersStudyDesign()
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    jobs = [(design, i, str(folder)) for i in range(design.subjects)]
    rows = []
    if processes > 1:
        with ProcessPoolExecutor(processes) as pool:
            for k, out in enumerate(pool.map(_make_subject, jobs, chunksize=2), start=1):
                rows += out
                if progress is not None and k % 10 == 0:
                    print(f"{k} of {len(jobs)} subjects", file=progress, flush=True)
    else:
        for job in jobs:
            rows += _make_subject(job)
    truth = pd.DataFrame(rows)
    with atomic_output(folder / "README.md") as tmp:
        tmp.write_text(_readme(design), encoding="utf-8")
    with atomic_output(truth_path) as tmp:
        truth.to_csv(tmp, index=False)
    return truth


def _readme(design: LayersStudyDesign) -> str:
    return ("# SYNTHETIC study of subjects with their own layers: NOT measurements\n\n"
            "Made by the workflow (rule make_layers_study, "
            "`skinsuction.evaluation.make_layers_study`): FE virtual experiments at each "
            "subject's own layers, plus noise; the truth is in a separate file.\n\n"
            "Design:\n\n" + "\n".join(f"- {k}: {v}" for k, v in asdict(design).items()) + "\n")


def _interval_holds(rows: pd.DataFrame, truth: pd.Series, name: str) -> pd.Series:
    """Whether each interval holds the truth; an open end (its flag, or no value) holds
    all beyond it: there the data do not bound the parameter."""
    def is_open(end):
        flag = rows.get(f"{name}_{end}_open")
        missing = rows[f"{name}_{end}_mpa"].isna()
        return missing if flag is None else missing | flag.fillna(False).astype(bool)

    lo, hi = rows[f"{name}_lower_mpa"], rows[f"{name}_upper_mpa"]
    return (is_open("lower") | (lo <= truth)) & (is_open("upper") | (truth <= hi))


def layers_study_check(curves: pd.DataFrame, truth: pd.DataFrame) -> dict:
    """What ``skinsuction study`` found in the synthetic study, against its truth.

    Parameters
    ----------
    curves : pandas.DataFrame
        The study's ``curves.parquet``.
    truth : pandas.DataFrame
        The truth written by :func:`make_layers_study`.

    Returns
    -------
    dict
        ``per_measurement``: rows of the coverage of the 95 % intervals of X1d and
        X1h (an open end counts as holding), the median and 95th percentile of
        the X1d error, the causes named and the verdicts, per kind of measurement
        (ramp, mode 1); ``groups``: per kind, the study's own group comparison
        (:func:`skinsuction.cohort.compare_groups`: the treated/control change of
        the median log X1d, its bootstrap interval, the Mann-Whitney p) on the
        estimates and on the true X1d of the same subjects.
    """
    from skinsuction.cohort import compare_groups

    c = curves.copy()
    c["file_name"] = c["file"].map(lambda f: Path(str(f)).name)
    merged = c.merge(truth.add_prefix("true_"), left_on="file_name", right_on="true_file",
                     how="left", validate="many_to_one")
    if merged["true_x1d_mpa"].isna().any():
        lost = merged.loc[merged["true_x1d_mpa"].isna(), "file_name"].tolist()
        raise ValueError(f"measurements without a truth: {lost[:5]}")
    per, groups = [], []
    for kind, rows in merged.groupby("true_measurement", sort=True):
        ok = rows[rows["x1d_mpa"].notna()]
        err = (ok["x1d_mpa"] / ok["true_x1d_mpa"] - 1).abs()
        holds_d = _interval_holds(ok, ok["true_x1d_mpa"], "x1d")
        holds_h = _interval_holds(ok, ok["true_x1h_mpa"], "x1h")
        causes = rows["cause"].fillna("(error)").value_counts().to_dict()
        # the verdict says what a cause stands on (beyond_space: an edge of the space)
        verdicts = (rows["verdict"].fillna("(error)").value_counts().to_dict()
                    if "verdict" in rows else {})
        per.append({"measurement": kind, "n": len(rows), "identified": len(ok),
                    "x1d_covered": int(holds_d.sum()), "x1h_covered": int(holds_h.sum()),
                    "x1d_coverage": float(holds_d.mean()) if len(ok) else math.nan,
                    "x1h_coverage": float(holds_h.mean()) if len(ok) else math.nan,
                    "x1d_error_median": float(err.median()) if len(ok) else math.nan,
                    "x1d_error_p95": float(err.quantile(0.95)) if len(ok) else math.nan,
                    "causes": "; ".join(f"{k} {v}" for k, v in sorted(causes.items())),
                    "verdicts": "; ".join(f"{k} {v}" for k, v in sorted(verdicts.items()))})
        for what, col in (("estimates", "x1d_mpa"), ("truth", "true_x1d_mpa")):
            # the study's own comparison (comparison.csv), on the estimates and on the truth
            frame = pd.DataFrame({"group": ok["true_group"].to_numpy(),
                                  "x1d_mpa": ok[col].to_numpy(float)})
            for r in compare_groups(frame, reference="control", seed=0)[0]:
                groups.append({"measurement": kind, "on": what, "n": r["n"],
                               **{k: r.get(k) for k in ("median_change_percent",
                                                        "ci_low_percent", "ci_high_percent",
                                                        "p_value")}})
    return {"per_measurement": per, "groups": groups}


def layers_study_markdown(check: dict, design: LayersStudyDesign, seconds=None) -> str:
    """The check as Markdown: coverage and verdicts, then the group comparison."""
    lines = ["# The synthetic study of subjects with their own layers, against its truth", "",
             f"SYNTHETIC: {design.subjects} subjects (seed {design.seed}), each with its own "
             f"layers given with sd {design.thickness_sd:g} mm; the treated half's dermis "
             f"x {design.effect:g}.", ""]
    if seconds is not None:
        lines += [f"`skinsuction study` took {seconds:.0f} s.", ""]
    lines += ["| measurement | n | identified | X1d interval holds the truth | X1h | "
              "median X1d error | 95th pct | causes named | verdicts |",
              "|---|---|---|---|---|---|---|---|---|"]
    for r in check["per_measurement"]:
        lines.append(f"| {r['measurement']} | {r['n']} | {r['identified']} | "
                     f"{r['x1d_covered']} ({100 * r['x1d_coverage']:.0f} %) | "
                     f"{r['x1h_covered']} ({100 * r['x1h_coverage']:.0f} %) | "
                     f"{100 * r['x1d_error_median']:.2f} % | {100 * r['x1d_error_p95']:.2f} % | "
                     f"{r['causes']} | {r['verdicts']} |")
    lines += ["", "Treated against control, the study's comparison (median log X1d, "
              "Mann-Whitney U), on the estimates and on the truth:", "",
              "| measurement | on | n | median change | bootstrap 95 % | p |",
              "|---|---|---|---|---|---|"]
    for g in check["groups"]:
        lines.append(f"| {g['measurement']} | {g['on']} | {g['n']} | "
                     f"{g['median_change_percent']:+.1f} % | {g['ci_low_percent']:+.1f} … "
                     f"{g['ci_high_percent']:+.1f} % | {g['p_value']:.2g} |")
    return "\n".join(lines) + "\n"
