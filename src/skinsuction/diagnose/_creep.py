"""Viscoelastic creep as a cause: its name, its hypothesis, and why a ramp cannot test it.

Shared by the ramp diagnosis (:mod:`._diagnose`) and the time-curve one (:mod:`._time`).
"""

__all__ = ["VISCOELASTIC_CREEP", "HYPOTHESIS", "untestable_on_ramps"]

#: Name of the cause in reports.
VISCOELASTIC_CREEP = "viscoelastic_creep"

HYPOTHESIS = ("the layers relax: a Prony spectrum over the neo-Hookean layers, X1 at long "
              "times and X1 (1 + sum g) at once; the deflection creeps at a constant suction "
              "and recovers slowly after its release")


def untestable_on_ramps() -> dict:
    """The note every pressure-ramp diagnosis carries about creep."""
    return {"cause": VISCOELASTIC_CREEP,
            "reason": "an ascending pressure ramp without time cannot tell a rate effect "
                      "(creep) from a softer or stiffer elastic curve: measure a time curve "
                      "(mode 1 or mode 2, probe_mm,time_s,pressure_mbar,deflection_mm) to "
                      "test it"}
