"""Make data/synthetic_study/: a SYNTHETIC clinical study (not a measurement).

30 subjects (S01..S15 treated, S16..S30 control) x 2 visits x 2 probes (6 mm and
2 mm), one CSV per subject-visit (S01_v1.csv, ...), pressures 0, 2, ..., 100 mbar.
The curves are the FE model's (skinsuction.space.solve_with_fallbacks: reference
mesh, fixed bottom, both layers 1 mm thick, neo-Hookean; quad9 fallback, spliced)
at drawn moduli, plus Gaussian noise on every deflection but the one at 0 mbar
(the instrument zero).  Treated subjects' dermis is 25 % stiffer at visit 2 (the
hidden effect).  The truth goes to data/synthetic_study_truth.csv, never into the
study's files.  One draw from NumPy default_rng(2026), constants below.

S17_v2.csv is broken ON PURPOSE (a decimal comma in one deflection of its 2 mm
curve, so that row has too many fields), to exercise the loader's error path.

    nice -n 5 python data/make_synthetic_study.py
"""

import subprocess
import time
from pathlib import Path

import numpy as np

from skinsuction.provenance import git_info
from skinsuction.space import solve_with_fallbacks

SEED = 2026  # the one seed of every draw
SUBJECTS = [f"S{i:02d}" for i in range(1, 31)]
GROUP = {s: "treated" if i < 15 else "control" for i, s in enumerate(SUBJECTS)}  # S01..S15 treated
# Dermis X1 (MPa), log-normal across subjects.  Diridollou et al. 2000 (Skin Res
# Technol 6:214; suction, volar forearm, 10 men): E = 129 +- 88 kPa; neo-Hookean
# X1 = E/6 = 0.0215 MPa.  Median 0.02 MPa; log-sd 0.45 is chosen (88/129 read as a
# log-normal spread would be 0.62), clipped to a chosen range.
X1D_MEDIAN, X1D_LOG_SD, X1D_CLIP = 0.02, 0.45, (0.008, 0.08)
RATIO_RANGE = (0.01, 0.1)  # X1h/X1d, log-uniform; chosen (the paper's test point: 0.075)
EFFECT = {"treated": 1.25, "control": 1.0}  # X1d factor at visit 2: the hidden effect (chosen)
VISIT_LOG_SD = 0.05  # visit-to-visit biological variation of X1d and X1h, each (chosen)
NOISE_UM = (1.0, 3.0)  # noise sd per subject-visit, uniform (chosen; example file: 1.5 um)
PRESSURES = np.arange(0.0, 101.0, 2.0)  # mbar, both probes
PROBES = (6.0, 2.0)  # aperture diameters, mm; the 6 mm curve first in each file
MESH = {"refinement": 1.0}  # the reference mesh
FALLBACK = [{"element": "quad9", "quadrature": "full", "wall_penalty": 1.0, "iterations_per_step": 30}]
MAX_DRAWS = 10  # draws of one subject before giving up
BROKEN = ("S17", 2, 2.0, 40.0)  # subject, visit, probe, pressure of the decimal comma
HERE = Path(__file__).resolve().parent
OUT_DIR, TRUTH = HERE / "synthetic_study", HERE / "synthetic_study_truth.csv"


def draw_subject(rng, group):
    """Moduli (x1d, x1h) and noise sd (mm) of both visits of one subject."""
    x1d = float(np.clip(X1D_MEDIAN * np.exp(X1D_LOG_SD * rng.standard_normal()), *X1D_CLIP))
    x1h = x1d * float(np.exp(rng.uniform(*np.log(RATIO_RANGE))))
    visits = []
    for visit in (1, 2):
        fd, fh = np.exp(VISIT_LOG_SD * rng.standard_normal(2))
        effect = EFFECT[group] if visit == 2 else 1.0
        visits.append((x1d * effect * fd, x1h * fh, 1e-3 * rng.uniform(*NOISE_UM)))
    return visits


def model_commit():
    commit = git_info().get("commit") or "unknown"
    src = HERE.parent / "src" / "skinsuction"
    status = subprocess.run(["git", "status", "--porcelain", "--", "model", "space.py"],
                            capture_output=True, text=True, cwd=src).stdout
    return commit + (" (model sources with uncommitted changes)" if status.strip() else "")


def main():
    start = time.perf_counter()
    rng = np.random.default_rng(SEED)
    OUT_DIR.mkdir(exist_ok=True)
    truth, redraws, fallbacks, solves = [], [], 0, 0
    for subject in SUBJECTS:
        t0, group = time.perf_counter(), GROUP[subject]
        for draw in range(1, MAX_DRAWS + 1):
            visits, curves, ok = draw_subject(rng, group), [], True
            for visit, (x1d, x1h, _) in enumerate(visits, start=1):
                solved = {}
                for probe in PROBES:
                    params = {"x1d": x1d, "x1h": x1h, "probe_mm": probe, "bottom": "fixed"}
                    c, kept, _ = solve_with_fallbacks(params, PRESSURES, mesh=MESH, fallback=FALLBACK,
                                                      label=f"{subject}_v{visit} {probe:g} mm",
                                                      splice=True)
                    solves += 1
                    solved[probe] = (c, kept)
                    ok = ok and c.converged and bool(np.isfinite(c.deflection_mm).all())
                curves.append(solved)
            if ok:
                break
            redraws.append(f"{subject} (draw {draw})")
            print(f"{subject}: a curve stopped before 100 mbar, redrawing")
        else:
            raise SystemExit(f"{subject}: no draw in {MAX_DRAWS} reached 100 mbar")
        for visit, ((x1d, x1h, sd), solved) in enumerate(zip(visits, curves), start=1):
            rows = []
            for probe in PROBES:
                m = solved[probe][0].deflection_mm + rng.normal(0.0, sd, PRESSURES.size)
                m[PRESSURES == 0] = 0.0  # the instrument zeroes there
                for p, x in zip(PRESSURES, m):
                    text = f"{x:.5f}"
                    if (subject, visit, probe, p) == BROKEN:
                        text = text.replace(".", ",")  # broken on purpose, see the docstring
                    rows.append(f"{probe:g},{p:g},{text}")
            head = ["# SYNTHETIC STUDY, NOT A MEASUREMENT. Made by data/make_synthetic_study.py",
                    f"# subject: {subject}", f"# group: {group}", f"# visit: {visit}",
                    "# site: volar_forearm", "probe_mm,pressure_mbar,deflection_mm"]
            (OUT_DIR / f"{subject}_v{visit}.csv").write_text("\n".join(head + rows) + "\n",
                                                              encoding="utf-8")
            kept = ";".join(f"{p:g}:{solved[p][1]}" for p in PROBES)
            fallbacks += sum(solved[p][1] > 0 for p in PROBES)
            truth.append(f"{subject},{group},{visit},{x1d:.6g},{x1h:.6g},{1e3 * sd:.4g},{kept}")
        print(f"{subject} ({group}): draw {draw}, fallbacks "
              f"{' / '.join(t.rsplit(',', 1)[1] for t in truth[-2:])}, {time.perf_counter() - t0:.1f} s")
    commit = model_commit()
    head = ["# SYNTHETIC STUDY TRUTH, NOT A MEASUREMENT. Made by data/make_synthetic_study.py",
            f"# for the files of data/synthetic_study/; NumPy default_rng seed {SEED}",
            "# hidden effect: X1d x 1.25 (+25 %) at visit 2 in the treated group (S01..S15),",
            f"# x 1.0 in the control group; visit-to-visit log-sd {VISIT_LOG_SD} on X1d and X1h",
            "# fe_fallback: probe_mm:index of the solve that carried the curve (0 first, 1 quad9)",
            f"# redraws: {', '.join(redraws) or 'none'}",
            f"# model_git_commit: {commit}",
            "subject,group,visit,x1d_mpa,x1h_mpa,noise_um,fe_fallback"]
    TRUTH.write_text("\n".join(head + truth) + "\n", encoding="utf-8")
    (OUT_DIR / "README.md").write_text("\n".join([
        "# Synthetic study (NOT a measurement)",
        "",
        "A made-up clinical suction study for the study/cohort feature, written by",
        "`data/make_synthetic_study.py` from the skinsuction FE model plus Gaussian noise.",
        "Design: 30 subjects (S01..S15 treated, S16..S30 control) x 2 visits x 2 probes",
        "(6 mm and 2 mm), 0..100 mbar; one file per subject-visit (`S01_v1.csv`, ...).",
        "Hidden effect: the dermis modulus X1d of treated subjects rises by 25 % at visit 2.",
        "The true moduli are in `data/synthetic_study_truth.csv`, not in this folder.",
        "`S17_v2.csv` is broken on purpose (a decimal comma in one 2 mm deflection).",
        f"Model git commit: {commit}.",
    ]) + "\n", encoding="utf-8")
    print(f"wrote {len(truth)} files in {OUT_DIR}, {TRUTH}: {solves} FE curves, "
          f"{fallbacks} curves carried by the fallback, {len(redraws)} redraws, "
          f"{time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    main()
