"""Helpers for the built-FMU tests: one FMU instance through fmpy with its log captured."""

from __future__ import annotations

from fmpy import read_model_description
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
    fmi2StepFinishedTYPE,
)

from wheelterrain.cosim.master import set_values


class Instance:
    """An instantiated FMU with a name -> value-reference map and a captured log."""

    def __init__(self, fmu_path, unzip_dir, name="instance"):
        from fmpy import calloc, free

        md = read_model_description(str(fmu_path))
        self.md = md
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.types = {v.name: v.type for v in md.modelVariables}
        self.log: list[tuple[int, str]] = []

        def logger(component, instance, status, category, message):
            self.log.append((status, message.decode("utf-8", "replace")))

        callbacks = fmi2CallbackFunctions()
        callbacks.logger = fmi2CallbackLoggerTYPE(logger)
        callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        callbacks.stepFinished = fmi2StepFinishedTYPE()
        self._callbacks = callbacks  # keep the ctypes objects alive
        self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzip_dir,
                             modelIdentifier=md.coSimulation.modelIdentifier,
                             instanceName=name)
        self.fmu.instantiate(callbacks=callbacks, loggingOn=True)

    def start(self, values=None):
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        if values:
            self.set(values)
        self.fmu.exitInitializationMode()
        return self

    def set(self, values):
        set_values(self.fmu, self.vr, self.types, values)

    def get(self, *names):
        values = self.fmu.getReal([self.vr[n] for n in names])
        return values[0] if len(names) == 1 else values

    def errors(self):
        return [m for status, m in self.log if status >= 2]

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()
