"""One FMU instance through fmpy, addressed by variable name.

The one wrapper every caller of a built FMU uses: the C1-C4 master and the MPC's FMU plant
(:mod:`wheelterrain.cosim.master`), the sweep's workers (:mod:`wheelterrain.cosim.sweep`), the
built-FMU tests and the benchmarks. It keeps the name -> value-reference and name -> type maps
of the modelDescription, sets each value with its type's setter, optionally captures the FMU's
log, and on :meth:`close` terminates only what was initialised and removes the folder it
extracted itself.
"""

from __future__ import annotations

import shutil
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path

from wheelterrain.errors import FMUError


def set_values(fmu, vr: Mapping[str, int], types: Mapping[str, str], values: Mapping,
               where: str = "the FMU") -> None:
    """Set ``values`` (by variable name) on an fmpy FMU2Slave with the setter of each
    variable's type (Integer values rounded: table integers are whole numbers). A name the FMU
    lacks means it was built from another version of the parameter table: FMUError."""
    missing = [name for name in values if name not in types]
    if missing:
        raise FMUError(
            f"{where} has no variable {missing[0]!r} ({len(missing)} missing): it was built by "
            "another version of wheelterrain; rebuild it with `wheelterrain build` (add "
            "`--flavor native` for the native FMUs)")
    for name, value in values.items():
        kind = types[name]
        if kind in ("Real", "Float64"):
            fmu.setReal([vr[name]], [float(value)])
        elif kind in ("Integer", "Int32", "Enumeration"):
            fmu.setInteger([vr[name]], [round(value)])
        else:
            fmu.setBoolean([vr[name]], [bool(value)])


class _Fmi3:
    """An fmpy FMI 3.0 instance (FMU3Slave or FMU3Model) behind the FMI 2 method names the
    callers use (getReal, setReal, setInteger, doStep, getDerivatives, ...), so the C1-C4
    master, the coupling and the tests run either standard unchanged."""

    def __init__(self, fmu, md) -> None:
        self.raw = fmu
        self._experiment = (0.0, None)  # FMI 3 passes start and stop on entering initialisation
        self._enumerations = {v.valueReference for v in md.modelVariables
                              if v.type == "Enumeration"}

    def __getattr__(self, name):  # the calls named alike in both standards
        return getattr(self.raw, name)

    def instantiate(self, callbacks=None, loggingOn=False) -> None:
        self.raw.instantiate(loggingOn=loggingOn, logMessage=callbacks)

    def setupExperiment(self, startTime=0.0, stopTime=None) -> None:
        self._experiment = (startTime, stopTime)

    def enterInitializationMode(self) -> None:
        start, stop = self._experiment
        self.raw.enterInitializationMode(startTime=start, stopTime=stop)

    def getReal(self, vrs):
        return self.raw.getFloat64(vrs)

    def setReal(self, vrs, values) -> None:
        self.raw.setFloat64(vrs, values)

    def setInteger(self, vrs, values) -> None:
        for vr, value in zip(vrs, values, strict=True):
            (self.raw.setInt64 if vr in self._enumerations else self.raw.setInt32)([vr], [value])

    def doStep(self, t: float, h: float) -> None:
        self.raw.doStep(t, h)

    def newDiscreteStates(self):
        return self.raw.updateDiscreteStates()

    def getDerivatives(self, dx, nx) -> None:
        self.raw.getContinuousStateDerivatives(dx, nx)


def read_description(path: str | Path):
    """fmpy's model description of the FMU at ``path``; a file that is not an FMU fmpy can
    read is one FMUError naming it (not zipfile's traceback)."""
    from fmpy import read_model_description

    path = Path(path)
    if not path.is_file():
        raise FMUError(f"{path} not found: run `wheelterrain build`")
    try:
        return read_model_description(str(path))
    except Exception as err:  # fmpy raises zipfile's, lxml's or its own errors
        raise FMUError(f"{path} is not an FMU fmpy can read ({type(err).__name__}: {err}); "
                       "`wheelterrain build` writes WheelTerrain.fmu and SingleWheelRig.fmu"
                       ) from None


class Instance:
    """An instantiated FMI 2.0 or 3.0 FMU: co-simulation (``interface="cs"``, :attr:`fmu` an
    fmpy FMU2Slave) or model exchange (``"me"``, an FMU2Model; :meth:`start` leaves it in
    continuous-time mode). An FMI 3.0 FMU is driven through fmpy's FMI 3 API behind the same
    method names (:class:`_Fmi3`).

    ``unzip`` is the folder the FMU was extracted to (None: extract it here and remove it on
    :meth:`close`). With ``log=True`` every message the FMU logs is kept in :attr:`log` as
    (status, text) and :meth:`errors` lists those of status discard, error or fatal.
    """

    def __init__(self, path: str | Path, unzip: str | None = None, name: str = "instance",
                 log: bool = False, interface: str = "cs") -> None:
        from fmpy import extract
        from fmpy.fmi2 import FMU2Model, FMU2Slave
        from fmpy.fmi3 import FMU3Model, FMU3Slave

        self.path = Path(path)
        self.md = read_description(path)
        self.interface = interface
        kind = {"cs": self.md.coSimulation, "me": self.md.modelExchange}[interface]
        if kind is None:
            which = "model-exchange" if interface == "me" else "co-simulation"
            raise FMUError(f"{path} has no {which} interface (the native FMUs have both: "
                           "`wheelterrain build --flavor native` writes them to build/native)")
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.types = {v.name: v.type for v in self.md.modelVariables}
        self.log: list[tuple[int, str]] = []
        self.running = False  # initialised (fmi2Terminate is legal only then)
        self._own_unzip = unzip is None
        self.unzip = extract(str(path)) if unzip is None else unzip
        try:
            fmi3 = self.md.fmiVersion.startswith("3")
            if fmi3:
                self._callbacks = self._log_message if log else None
                make = FMU3Slave if interface == "cs" else FMU3Model
            else:
                self._callbacks = self._logging_callbacks() if log else None
                make = FMU2Slave if interface == "cs" else FMU2Model
            self.fmu = make(guid=self.md.guid, unzipDirectory=self.unzip,
                            modelIdentifier=kind.modelIdentifier, instanceName=name)
            if fmi3:
                self.fmu = _Fmi3(self.fmu, self.md)
            self.fmu.instantiate(callbacks=self._callbacks, loggingOn=log)
        except BaseException:
            self._remove_unzip()
            raise

    def _log_message(self, environment, status, category, message) -> None:
        """FMI 3's log callback."""
        self.log.append((status, message.decode("utf-8", "replace")))

    def _logging_callbacks(self):
        from fmpy import calloc, free
        from fmpy.fmi2 import (
            fmi2CallbackAllocateMemoryTYPE,
            fmi2CallbackFreeMemoryTYPE,
            fmi2CallbackFunctions,
            fmi2CallbackLoggerTYPE,
            fmi2StepFinishedTYPE,
        )

        def logger(component, instance, status, category, message):
            self.log.append((status, message.decode("utf-8", "replace")))

        callbacks = fmi2CallbackFunctions()
        callbacks.logger = fmi2CallbackLoggerTYPE(logger)
        callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        callbacks.stepFinished = fmi2StepFinishedTYPE()
        return callbacks  # kept on self: the ctypes objects must outlive the instance

    def start(self, values: Mapping | None = None, stop: float | None = None) -> Instance:
        """Initialise at t = 0 with ``values`` set in initialisation mode; returns self."""
        self.fmu.setupExperiment(startTime=0.0, stopTime=stop)
        self.fmu.enterInitializationMode()
        if values:
            self.set(values)
        self.fmu.exitInitializationMode()
        self.running = True
        if self.interface == "me":  # event iteration, then continuous-time mode
            while self.fmu.newDiscreteStates()[0]:  # newDiscreteStatesNeeded
                pass
            self.fmu.enterContinuousTimeMode()
        return self

    def set(self, values: Mapping) -> None:
        set_values(self.fmu, self.vr, self.types, values, where=str(self.path))

    def refs(self, names: Iterable[str]) -> list[int]:
        return [self.vr[n] for n in names]

    def get(self, names: Iterable[str]) -> list[float]:
        """The Real variables ``names``, in that order."""
        return self.fmu.getReal(self.refs(names))

    def lane(self, refs: Sequence[int]) -> tuple[Callable[[], list[float]],
                                                 Callable[[Sequence[float]], None]]:
        """``(get, put)`` for the Real variables of value references ``refs``, a master's inner
        loop: ``get()`` their values, ``put(values)`` sets them, through the FMU's own
        fmi2GetReal / fmi2SetReal (fmi3GetFloat64 / fmi3SetFloat64, as fmpy loaded them: a
        status that is not OK raises as fmpy's getReal does) with the references and a value
        buffer made once, where fmpy's getReal makes both at every call."""
        import ctypes

        n = len(refs)
        fmi3 = isinstance(self.fmu, _Fmi3)
        raw = self.fmu.raw if fmi3 else self.fmu
        vr = (ctypes.c_uint32 * n)(*refs)
        buffer = (ctypes.c_double * n)()
        if fmi3:
            def get() -> list[float]:
                raw.fmi3GetFloat64(raw.component, vr, n, buffer, n)
                return buffer[:]

            def put(values: Sequence[float]) -> None:
                buffer[:] = values
                raw.fmi3SetFloat64(raw.component, vr, n, buffer, n)
        else:
            def get() -> list[float]:
                raw.fmi2GetReal(raw.component, vr, n, buffer)
                return buffer[:]

            def put(values: Sequence[float]) -> None:
                buffer[:] = values
                raw.fmi2SetReal(raw.component, vr, n, buffer)
        return get, put

    def value(self, name: str) -> float:
        """The Real variable ``name``."""
        return self.fmu.getReal([self.vr[name]])[0]

    def errors(self) -> list[str]:
        """Logged messages of status discard (2), error (3) or fatal (4); needs ``log=True``."""
        return [m for status, m in self.log if status >= 2]

    def close(self) -> None:
        try:
            if self.running:  # an FMU refuses fmi2Terminate before initialisation has ended
                self.running = False
                self.fmu.terminate()
        finally:
            self.fmu.freeInstance()
            self._remove_unzip()

    def _remove_unzip(self) -> None:
        if self._own_unzip:
            shutil.rmtree(self.unzip, ignore_errors=True)

    def __enter__(self) -> Instance:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
