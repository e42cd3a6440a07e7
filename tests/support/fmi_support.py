"""A minimal fmpy driver for tests: one FMU instance, values by name."""
from __future__ import annotations

import shutil

from fmpy import calloc, extract, free, read_model_description
from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                       fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)


class FmuInstance:
    """Instantiate, set parameters, initialise; then ``step`` and ``get``.  With
    ``initialise=False`` the instance stays in Initialization Mode until :meth:`initialise`;
    with ``setup=False`` it stays instantiated (no fmi2SetupExperiment, no parameters)."""

    def __init__(self, path, parameters=None, instance_name="instance", initialise=True, setup=True):
        self.md = read_model_description(str(path))
        self.vars = {v.name: v for v in self.md.modelVariables}
        self.dir = extract(str(path))
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=self.dir,
                             modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=instance_name)
        self.messages = []
        # Keep the callbacks referenced for the instance's lifetime.
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = fmi2CallbackLoggerTYPE(self._log)
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        self.fmu.instantiate(callbacks=self.callbacks, loggingOn=True)
        self.time = 0.0
        if not setup:
            return
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        for name, value in (parameters or {}).items():
            self.set(name, value)
        if initialise:
            self.initialise()

    def initialise(self):
        """fmi2ExitInitializationMode."""
        self.fmu.exitInitializationMode()

    def _log(self, component, instance, status, category, message):
        self.messages.append(message.decode() if isinstance(message, bytes) else message)

    def set(self, name, value):
        v = self.vars[name]
        vr = [v.valueReference]
        {"Real": lambda: self.fmu.setReal(vr, [float(value)]),
         "Integer": lambda: self.fmu.setInteger(vr, [int(value)]),
         "Boolean": lambda: self.fmu.setBoolean(vr, [bool(value)]),
         "String": lambda: self.fmu.setString(vr, [str(value)])}[v.type]()

    def get(self, name):
        v = self.vars[name]
        vr = [v.valueReference]
        return {"Real": lambda: self.fmu.getReal(vr)[0], "Integer": lambda: self.fmu.getInteger(vr)[0],
                "Boolean": lambda: self.fmu.getBoolean(vr)[0],
                "String": lambda: self.fmu.getString(vr)[0].decode()}[v.type]()

    def step(self, dt, **inputs):
        for name, value in inputs.items():
            self.set(name, value)
        self.fmu.doStep(currentCommunicationPoint=self.time, communicationStepSize=dt)
        self.time += dt

    def refused_step(self, dt=1e-3, **inputs):
        """Step expecting a refusal: assert it is not fmi2Fatal, return the ``error`` output."""
        import pytest
        from fmpy.fmi1 import FMICallException

        with pytest.raises(FMICallException) as info:
            self.step(dt, **inputs)
        assert info.value.status != 4, "never fmi2Fatal"
        return self.get("error")

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()
        shutil.rmtree(self.dir, ignore_errors=True)
