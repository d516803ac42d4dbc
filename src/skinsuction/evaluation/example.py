"""The shipped synthetic example ``data/example_suction_synthetic.csv`` and how it is made.

No public measured Cutometer curves exist, so the example is a virtual
experiment, labelled as synthetic in its ``#`` header: the FE model on a fine
mesh (``refinement`` 2, four times the elements of the reference mesh) with a
hidden effect, both probes, 51 pressures 0, 2, ..., 100 mbar, and Gaussian
noise of sd 2.5 µm on every deflection at p > 0 (a Cutometer reads the apex to
about 1-10 µm), NumPy seed 2024.

    python -m skinsuction.evaluation.example [OUT.csv]
"""

from __future__ import annotations

import sys

import numpy as np

__all__ = ["EXAMPLE", "make_example"]

#: Parameters of the example (moduli in MPa, hidden effect in its unit).
EXAMPLE = {
    "x1d": 0.03,
    "x1h": 3.6e-4,  # X1h / X1d = 0.012 (the paper's experimental X1h was 3.7e-4 MPa)
    "cause": "strain_stiffening",
    "value": 0.12,  # X2d in MPa (X2d / X1d = 4)
    "noise_um": 2.5,
    "seed": 2024,
    "mesh": {"refinement": 2.0},
    "pressures_mbar": list(np.arange(0.0, 101.0, 2.0)),
}


def make_example(out="data/example_suction_synthetic.csv", params=None):
    """Run the FE model and write the example CSV (a few minutes on one core)."""
    from skinsuction.provenance import git_info
    from skinsuction.space import default_registry

    from ._virtual import virtual_experiment, write_csv

    e = {**EXAMPLE, **(params or {})}
    cause = default_registry()[e["cause"]] if e["cause"] != "none" else None
    ve = virtual_experiment(e["x1d"], e["x1h"], cause, e["value"], noise_um=e["noise_um"],
                            seed=e["seed"], probes_mm=(6.0, 2.0),
                            pressures_mbar=e["pressures_mbar"], mesh=e["mesh"])
    if not ve.converged:
        raise RuntimeError("the FE model did not reach 100 mbar for the example")
    info = git_info()
    commit = (info.get("commit") or "unknown") + (" (working tree with uncommitted changes)"
                                                   if info.get("dirty") else "")
    header = [
        "Made by skinsuction.evaluation.example.make_example (python -m skinsuction.evaluation.example)",
        "with the skinsuction FE model on a fine mesh (refinement 2), fixed bottom, hypodermis 1 mm,",
        "a hidden effect (true_cause below) and Gaussian noise on every deflection at p > 0.",
        "subject: synthetic",
        f"git_commit: {commit}",
    ]
    return write_csv(ve, out, header)


if __name__ == "__main__":  # pragma: no cover
    print(make_example(*sys.argv[1:]))
