"""Multi-pass: the single-wheel rig run N times over the same strip of soil.

Each pass is the rig's quasi-static operating point (the sinkage that carries the load at the
slip, grouser-period mean, as ``wheelterrain steady``) on the soil the passes before it left:
pass k meets the rut of pass k - 1 (``soil.rut_depth``, with the pressure it carried,
``soil.rut_pressure``) and leaves its own (the contact's ``rut_left`` and
``rut_pressure_left``). With ``model.soil_memory`` = 1 the soil is elastic-plastic
(:class:`wheelterrain.model.contact.Rut`): in the rut it answers elastically up to the pressure
it carried and plastically beyond, and the contact begins at the rut's surface. With 0 every
pass meets virgin soil and the passes are identical.

The soil's strength and pressure-sinkage constants are those of the virgin soil in every pass:
the literature found here gives no rule for how one pass changes them (density, modulus,
shear strength per pass) that the model could take with a source, so the multi-pass effect
here is the rut's geometry and its stress history only: the pressure it carried and, with
``model.rut_shear`` = 1, the shear displacement the pass before left, which a later pass
counts on from (the README's multi-pass section says what this reproduces and what not).

Tanaka, Takehana, Hurrell, Uno & Yoshida (ISTVS 2024) ran five passes of the Rashid rover's
wheel on FJS-1 and Toyoura sand; ``passes`` defaults to their five.
"""

from __future__ import annotations

from collections.abc import Mapping

from wheelterrain.model import api
from wheelterrain.parameters import ParameterSet

PASSES = 5
"""Passes of Tanaka et al. (ISTVS 2024) on the Rashid wheel."""
KEYS = ("pass", "traction_coefficient", "drawbar_pull", "sinkage", "sinkage_increment",
        "rut_met", "rut_left", "rut_pressure_left", "torque", "compaction_resistance",
        "gross_thrust", "contact_length", "entry_angle")
"""The keys of every pass's row (``wheelterrain multipass --json``), in print order."""
UNITS = {"pass": "1", "traction_coefficient": "1", "drawbar_pull": "N", "sinkage": "m",
         "sinkage_increment": "m", "rut_met": "m", "rut_left": "m", "rut_pressure_left": "Pa",
         "torque": "N.m", "compaction_resistance": "N", "gross_thrust": "N", "contact_length": "m",
         "entry_angle": "rad"}


def run(params: Mapping[str, float] | ParameterSet, load: float, slip: float,
        passes: int = PASSES, slip_definition: str = api.DEFAULT_DEFINITION) -> list[dict]:
    """One row per pass (:data:`KEYS`): traction coefficient = drawbar pull / load; sinkage
    from the original surface; ``sinkage_increment`` against the previous pass (the first:
    against the surface); ``rut_met`` the rut the pass ran in, ``rut_left`` the one it left
    and ``rut_pressure_left`` the pressure it carried. The first pass meets the rut of
    ``params`` (``soil.rut_depth``, 0 for virgin soil; ``soil.rut_pressure``).
    Raises the errors of :func:`wheelterrain.model.api.steady_state` (a load the wheel
    cannot carry, a parameter out of range)."""
    if not isinstance(passes, int) or passes < 1:
        raise ValueError(f"passes must be a whole number >= 1, not {passes!r}")
    ps = params if isinstance(params, ParameterSet) else ParameterSet(params)
    rut, pressure = ps["soil.rut_depth"], ps["soil.rut_pressure"]
    rows, previous = [], 0.0
    for k in range(1, passes + 1):
        here = ps.with_values({"soil.rut_depth": rut, "soil.rut_pressure": pressure})
        out = api.steady_state(here, load, slip, slip_definition)
        rows.append({
            "pass": k, "traction_coefficient": out["drawbar_pull"] / out["load"]
            if out["load"] > 0 else 0.0, "drawbar_pull": out["drawbar_pull"],
            "sinkage": out["sinkage"], "sinkage_increment": out["sinkage"] - previous,
            "rut_met": rut, "rut_left": out["rut_left"],
            "rut_pressure_left": out["rut_pressure_left"], "torque": out["torque"],
            "compaction_resistance": out["compaction_resistance"],
            "gross_thrust": out["gross_thrust"], "contact_length": out["contact_length"],
            "entry_angle": out["entry_angle"]})
        previous = out["sinkage"]
        if ps["model.soil_memory"] == 1:  # the next pass meets this one's rut
            rut, pressure = out["rut_left"], out["rut_pressure_left"]
    return rows
