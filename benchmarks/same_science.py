"""Same science across a refactoring: the numbers of one checkout against another's.

Runs, with whichever ``skinsuction`` is importable (``PYTHONPATH=<tree>/src``), a
fixed set of forward solves (2-8 mm probes, X2, pre-stretch, a soft corner, a
mode-1 history) and the README's identifications and diagnoses (fixed seeds, the
shipped space), and writes every number they produce to one JSON file:

    PYTHONPATH=/path/to/old/src python benchmarks/same_science.py run old.json
    python benchmarks/same_science.py run new.json
    python benchmarks/same_science.py compare old.json new.json

``compare`` prints, per case, how many numbers there are, how many differ and the
largest relative difference. The forward model is compared through whichever API the
checkout has (a ``Skin`` or the earlier positional moduli).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FORWARD = [  # (name, x1d, x1h, extra two-layer keywords, probe_mm)
    ("reference_2mm", 0.08, 4.1e-4, {}, 2.0),
    ("reference_4mm", 0.08, 4.1e-4, {}, 4.0),
    ("reference_6mm", 0.08, 4.1e-4, {}, 6.0),
    ("reference_8mm", 0.08, 4.1e-4, {}, 8.0),
    ("stiffening_6mm", 0.03, 5e-4, {"x2d": 0.3}, 6.0),
    ("prestretch_2mm", 0.02, 3e-4, {"prestretch": 1.05, "t_d": 1.3, "t_h": 2.7}, 2.0),
    ("soft_corner_6mm", 0.001, 1.01e-3, {}, 6.0),
]
COMMANDS = [  # (name, argv after `skinsuction`)
    ("identify_weighted", ["identify", "data/example_measured.csv", "--objective", "weighted"]),
    ("identify_single_6", ["identify", "data/example_measured.csv", "--objective", "single",
                           "--probe", "6"]),
    ("identify_4_8", ["identify", "data/example_measured_4_8mm.csv", "--objective", "weighted"]),
    ("identify_layers", ["identify", "data/example_measured_layers.csv", "--objective",
                         "weighted"]),
    ("identify_mode1", ["identify", "data/example_mode1.csv"]),
    ("diagnose", ["diagnose", "data/example_measured.csv"]),
]


def forward() -> dict:
    import numpy as np

    from skinsuction import model

    out = {}
    for name, x1d, x1h, extra, probe in FORWARD:
        if hasattr(model, "Skin"):
            curve = model.simulate(model.Skin.two_layer(x1d, x1h, **extra), probe)
        else:
            curve = model.simulate(x1d, x1h, probe_mm=probe, **extra)
        out[name] = [None if not np.isfinite(v) else float(v) for v in curve.deflection_mm]
    from skinsuction import viscoelastic as ve

    history = ve.mode1_history(pressure_mbar=300.0, on_s=1.0, off_s=1.0, cycles=1)
    spectrum = ve.Prony([0.5], [0.3])
    mesh = {"refinement": 0.5}
    if hasattr(model, "Skin"):
        h = ve.simulate_history(model.Skin.two_layer(0.03, 4e-4, spectrum=spectrum),
                                history.times_s, history.pressure_mbar, probe=2, mesh=mesh)
    else:
        h = ve.simulate_history(0.03, 4e-4, spectrum, history.times_s, history.pressure_mbar,
                                probe_mm=2, mesh=mesh)
    out["mode1_history_2mm"] = [float(v) for v in h.deflection_mm]
    return out


def numbers(obj, prefix=""):
    """Every number in a JSON value, by its path."""
    if isinstance(obj, bool) or obj is None:
        return {}
    if isinstance(obj, (int, float)):
        return {prefix: float(obj)}
    if isinstance(obj, dict):
        out = {}
        for k, v in obj.items():
            if k in ("seconds", "cpu_seconds", "elapsed_s", "wall_s", "cpu_s", "date", "time_s",
                     "commit"):
                continue  # run-dependent
            out.update(numbers(v, f"{prefix}.{k}" if prefix else str(k)))
        return out
    if isinstance(obj, list):
        out = {}
        for i, v in enumerate(obj):
            out.update(numbers(v, f"{prefix}[{i}]"))
        return out
    return {}


def commands() -> dict:
    out = {}
    for name, argv in COMMANDS:
        with tempfile.TemporaryDirectory() as tmp:
            start = time.perf_counter()
            run = subprocess.run([sys.executable, "-m", "skinsuction", *argv, "--out", tmp],
                                 cwd=ROOT, capture_output=True, text=True, env=os.environ)
            seconds = time.perf_counter() - start
            found = {}
            for path in sorted(Path(tmp).rglob("*.json")):
                found.update(numbers(json.loads(path.read_text()), path.name))
            out[name] = {"exit": run.returncode, "seconds": seconds, "numbers": found,
                         "stderr_tail": run.stderr.splitlines()[-3:]}
            print(f"{name}: exit {run.returncode}, {len(found)} numbers, {seconds:.1f} s",
                  file=sys.stderr)
    return out


def compare(a_path, b_path) -> None:
    a, b = json.loads(Path(a_path).read_text()), json.loads(Path(b_path).read_text())
    rows = []
    for name in a["forward"]:
        x, y = a["forward"][name], b["forward"].get(name)
        rows.append((f"forward {name}", *diff(dict(enumerate(x)), dict(enumerate(y or [])))))
    for name in a["commands"]:
        x, y = a["commands"][name], b["commands"].get(name, {})
        rows.append((f"{name} (exit {x['exit']}/{y.get('exit')})",
                     *diff(x["numbers"], y.get("numbers", {}))))
    print("| case | numbers | differ | largest relative difference | missing |")
    print("|---|---|---|---|---|")
    for row in rows:
        print("| " + " | ".join(str(v) for v in row) + " |")


def diff(x: dict, y: dict):
    # times are run-dependent (a record written before a key was skipped still has them)
    common = [k for k in x if k in y and "seconds" not in str(k)]
    differ, largest = 0, 0.0
    for k in common:
        u, v = x[k], y[k]
        if u is None or v is None:
            differ += (u is None) != (v is None)
            continue
        if u != v:
            differ += 1
            largest = max(largest, abs(u - v) / max(abs(u), abs(v), 1e-300))
    return len(common), differ, f"{largest:.1e}", len(set(x) ^ set(y))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="what", required=True)
    r = sub.add_parser("run")
    r.add_argument("out")
    c = sub.add_parser("compare")
    c.add_argument("a")
    c.add_argument("b")
    args = parser.parse_args(argv)
    if args.what == "compare":
        compare(args.a, args.b)
        return 0
    import skinsuction

    record = {"package": skinsuction.__file__, "forward": forward(), "commands": commands()}
    Path(args.out).write_text(json.dumps(record, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
