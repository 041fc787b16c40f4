"""The model: the wheel-terrain contact physics and the rig, written once.

Layers inside the package, each importing only those above it in this list:

- :mod:`.slip`: the two slip definitions and the slip's reference radius (no CasADi).
- :mod:`.soil`: the soil's laws (pressure-sinkage, shear, strength, bulldozing, the
  elastic-plastic soil a rut remembers).
- :mod:`.contact`: the contact's geometry and forms (arc and patch) on those laws, the wheel's
  plastic sinkage.
- :mod:`.solve`: the quasi-static sinkage solve (scan, Newton, the acceptance test).
- :mod:`.functions`: :func:`.functions.build` assembles every CasADi Function of the model
  from the contact and the solve, exact Jacobians included.
- :mod:`.rig`, :mod:`.rover`, :mod:`.ground`, :mod:`.multipass`: the single-wheel rig
  (carriage, wheel drive, vertical motion), the rover's chassis, the terrain map and rut
  record, the passes of one wheel over one strip.
- :mod:`.api`: the validated float API, also reachable here: ``model.steady_state``,
  ``model.contact_forces``, ``model.capacity``, ``model.steady_jacobian``, and for many points
  at once ``model.steady_states``, ``model.steady_map`` and ``model.contact_forces_many``
  (lane-parallel C, :mod:`.lanes`).

The float API is loaded on first use, so importing :mod:`.slip` alone (sweep workers) does not
load CasADi.
"""

from __future__ import annotations

_API = ("steady_state", "steady_states", "steady_map", "contact_forces", "contact_forces_many",
        "capacity", "steady_jacobian", "contact_radius", "RESIDUAL_TOLERANCE", "STEP_TOLERANCE")


def __getattr__(name: str):
    if name in _API:
        from . import api

        return getattr(api, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *_API])
