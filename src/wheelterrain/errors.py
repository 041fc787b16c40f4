"""Errors that name what was wrong and what would be valid."""

from __future__ import annotations

import numbers


def shown(value: object) -> str:
    """``value`` as a message shows it: a number as Python writes a float (a NumPy scalar was
    shown as np.float64(1.5)), anything else as its repr (a string in quotes)."""
    if isinstance(value, numbers.Real) and not isinstance(value, bool):
        return repr(float(value)) if not isinstance(value, numbers.Integral) else str(int(value))
    return repr(value)


class WheelTerrainError(ValueError):
    """Base class: bad input or an operating point the model cannot represent."""


class ParameterError(WheelTerrainError):
    """A parameter name or value is invalid. The message names the parameter and its valid range."""

    def __init__(self, name: str, value: object, problem: str) -> None:
        self.name = name
        self.value = value
        text = "" if value is None else f" = {shown(value)}"
        super().__init__(f"parameter {name}{text} {problem}")


class InputError(WheelTerrainError):
    """An input (slip, load, sinkage, ...) is invalid. The message names it and its valid range."""

    def __init__(self, name: str, value: object, problem: str) -> None:
        self.name = name
        self.value = value
        super().__init__(f"input {name} = {shown(value)} {problem}")


class LoadTooLargeError(WheelTerrainError):
    """The wheel cannot carry the load even fully buried (sinkage = contact radius)."""

    def __init__(self, load: float, capacity: float, radius: float) -> None:
        self.load = load
        self.capacity = capacity
        super().__init__(
            f"load {load:g} N exceeds what the wheel can carry even fully buried: the normal force "
            f"at sinkage = contact radius ({radius:g} m) is {capacity:.6g} N. Lower the load, or "
            "use a stiffer soil or a wider/larger wheel (soil.k_phi, wheel.width, wheel.radius)."
        )


class SolveError(WheelTerrainError):
    """The quasi-static sinkage solve did not converge (never returned as a number)."""


class UsageError(WheelTerrainError):
    """A request that cannot be carried out as asked, found before any work: an engine that
    cannot run the scenario, an option that does not apply, FMUs that are not built. The message
    says why and what would work (the command line's exit code 2)."""


class CosimulationError(WheelTerrainError):
    """An FMU refused a call during a co-simulation run (the model left its domain: a load the
    soil cannot carry, a wheel buried past its axle, ...). The FMU logs the reason; the message
    names the case and the call."""


class FMUError(WheelTerrainError):
    """An FMU given to a master does not fit this version (e.g. built from another table)."""


class CalibrationError(WheelTerrainError):
    """A calibration request that cannot be carried out (unknown case or parameter, ...)."""


class DataError(WheelTerrainError):
    """A test-data file that cannot be read as documented in :mod:`wheelterrain.fit.datasets`;
    the message names the line and what is wrong."""
