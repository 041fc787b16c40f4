"""Errors that name what was wrong and what would be valid."""

from __future__ import annotations


class WheelTerrainError(ValueError):
    """Base class: bad input or an operating point the model cannot represent."""


class ParameterError(WheelTerrainError):
    """A parameter name or value is invalid. The message names the parameter and its valid range."""

    def __init__(self, name: str, value: object, problem: str) -> None:
        self.name = name
        self.value = value
        shown = "" if value is None else f" = {value!r}"
        super().__init__(f"parameter {name}{shown} {problem}")


class InputError(WheelTerrainError):
    """An input (slip, load, sinkage, ...) is invalid. The message names it and its valid range."""

    def __init__(self, name: str, value: object, problem: str) -> None:
        self.name = name
        self.value = value
        super().__init__(f"input {name} = {value!r} {problem}")


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
