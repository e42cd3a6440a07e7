"""Drive an FMI 3.0 co-simulation FMU through fmpy with the script of ``support.fmu_calls``.

The same calls as :class:`support.fmu_calls.Driver` (FMI 2.0) in FMI 3.0's functions:
``setup t0 stop`` keeps the experiment's times for ``enter`` (fmi3EnterInitializationMode
takes them), the FMU state's functions are ``fmi3GetFMUState`` ..., ``step`` is fmi3DoStep
(its outputs kept in ``last_step``).  :func:`as_fmi3` writes an FMI 2.0 message in FMI 3.0's
names, so an FMI 3.0 FMU's messages can be compared with its FMI 2.0 twin's.
"""
from __future__ import annotations

import re
import shutil

from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import FMU3Slave

from tests.support.fmu_calls import Step, Values

#: FMI 2.0's functions as FMI 3.0 names them (fmi2SetupExperiment's part is fmi3EnterInitializationMode's);
#: the others are fmi2X -> fmi3X.
NAMES = {"fmi2Instantiate": "fmi3InstantiateCoSimulation", "fmi2SetupExperiment": "fmi3EnterInitializationMode",
         "fmi2SetFMUstate": "fmi3SetFMUState", "fmi2GetFMUstate": "fmi3GetFMUState",
         "fmi2FreeFMUstate": "fmi3FreeFMUState", "fmi2SerializedFMUstateSize": "fmi3SerializedFMUStateSize",
         "fmi2SerializeFMUstate": "fmi3SerializeFMUState", "fmi2DeSerializeFMUstate": "fmi3DeserializeFMUState",
         "fmi2GetReal": "fmi3GetFloat64", "fmi2SetReal": "fmi3SetFloat64", "fmi2GetInteger": "fmi3GetInt32",
         "fmi2SetInteger": "fmi3SetInt32"}
TYPES = {"Real": "Float64", "Integer": "Int32"}


def as_fmi3(message: str) -> str:
    """``message`` of an FMI 2.0 native FMU as its FMI 3.0 twin words it."""
    message = re.sub(r"\bfmi2\w+", lambda m: NAMES.get(m.group(0), "fmi3" + m.group(0)[4:]), message)
    return re.sub(r"\b(a|not a) (Real|Integer)\b", lambda m: f"{m.group(1)} {TYPES[m.group(2)]}", message)


class Driver3(Values):
    """An instance of the FMI 3.0 FMU at ``path`` with a logger that keeps every message."""

    def __init__(self, path, instance: str = "inst", unzipped=None):
        self.md = read_model_description(str(path))
        self.variables = {v.name: v for v in self.md.modelVariables}
        self.dir = unzipped or extract(str(path))
        self._unzipped_here = unzipped is None
        self.log = []
        self.fmu = FMU3Slave(guid=self.md.guid, unzipDirectory=self.dir,
                             modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=instance)
        self.fmu.instantiate(logMessage=self._keep)
        self.states = {}
        self.experiment = (0.0, None)
        self.last_step = None

    def _keep(self, env, status, category, message):
        self.log.append((status, category.decode(), message.decode(errors="replace")))

    def _step(self, t, h):
        self.last_step = self.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)

    def call(self, op: str, *args):
        """One call of the script (as :meth:`support.fmu_calls.Driver.call`)."""
        f = self.fmu
        actions = {
            "set": lambda values: self._set(values),
            "get": lambda names: self._get(names),
            "setup": lambda t0, *stop: setattr(self, "experiment", (t0, stop[0] if stop else None)),
            "enter": lambda: f.enterInitializationMode(startTime=self.experiment[0], stopTime=self.experiment[1]),
            "exit": f.exitInitializationMode,
            "step": self._step,
            "getstate": lambda key: self.states.__setitem__(key, f.getFMUState()),
            "setstate": lambda key: f.setFMUState(self.states[key]),
            "serialize": lambda key: self.states.__setitem__(key, f.serializeFMUState(self.states[key])),
            "deserialize": lambda key: self.states.__setitem__(key, f.deserializeFMUState(self.states[key])),
            "bytes": lambda key, data: self.states.__setitem__(key, data),
            "terminate": f.terminate,
            "reset": f.reset,
        }
        self.log.clear()
        try:
            result, status = actions[op](*args), 0
        except FMICallException as exc:
            result, status = None, exc.status
        return Step((op, *args), status, result, list(self.log))

    def serialized(self, key) -> bytes:
        return self.fmu.serializeFMUState(self.states[key])

    def close(self):
        self.fmu.freeInstance()
        if self._unzipped_here:
            shutil.rmtree(self.dir, ignore_errors=True)
