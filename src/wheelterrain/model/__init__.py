"""The model: the wheel-terrain contact physics and the rig, written once.

- :mod:`.slip`: the two slip definitions and the slip's reference radius (no CasADi).
- :mod:`.contact`: the contact model (arc and patch forms) and :func:`.contact.build`, which
  makes every CasADi Function of the model, exact Jacobians included.
- :mod:`.solve`: the quasi-static sinkage solve those Functions contain (scan, Newton, the
  acceptance test).
- :mod:`.rig`: the single-wheel test rig (carriage, wheel drive, vertical motion).
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
