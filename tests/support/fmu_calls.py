"""Drive one FMU through fmpy with a script of FMI calls and record what it answers.

The equality tests of the native FMUs (tests/fmus/native/test_native_equality.py) run the same script
on a native FMU and on its pythonfmu twin and compare the traces: each call's status, the
values read, and every message the FMU logged (as the logger received it).
"""
from __future__ import annotations

import ctypes
import shutil
from dataclasses import dataclass, field

from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                       fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)

_calloc = ctypes.CDLL(None).calloc
_calloc.restype, _calloc.argtypes = ctypes.c_void_p, [ctypes.c_size_t, ctypes.c_size_t]
_free = ctypes.CDLL(None).free
_free.argtypes = [ctypes.c_void_p]


@dataclass
class Step:
    """One call's record: the call, its status (0 OK ... 3 error), what it returned, the messages."""

    call: tuple
    status: int
    result: object = None
    messages: list = field(default_factory=list)


class Values:
    """Set and get variables by name, grouped by type (fmpy's ``set<Type>``/``get<Type>``):
    what the FMI 2.0 and FMI 3.0 drivers share (``self.variables``, ``self.fmu``)."""

    def _by_type(self, names):
        groups = {}
        for name in names:
            v = self.variables[name]
            groups.setdefault(v.type, []).append((name, v.valueReference))
        return groups

    def _set(self, values: dict):
        for kind, pairs in self._by_type(values).items():
            getattr(self.fmu, f"set{kind}")([vr for _, vr in pairs], [values[n] for n, _ in pairs])

    def _get(self, names):
        got = {}
        for kind, pairs in self._by_type(names).items():
            read = getattr(self.fmu, f"get{kind}")([vr for _, vr in pairs])
            got.update({n: (x.decode() if isinstance(x, bytes) else x) for (n, _), x in zip(pairs, read)})
        return [got[n] for n in names]


class Driver(Values):
    """An instance of the FMU at ``path`` with a logger that keeps every message."""

    def __init__(self, path, instance: str = "inst", unzipped=None):
        self.md = read_model_description(str(path))
        self.variables = {v.name: v for v in self.md.modelVariables}
        self.dir = unzipped or extract(str(path))
        self._unzipped_here = unzipped is None
        self.log = []
        self._logger = fmi2CallbackLoggerTYPE(self._keep)
        self._callbacks = fmi2CallbackFunctions()
        self._callbacks.logger = self._logger
        self._callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(lambda n, size: _calloc(n, size))
        self._callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(lambda p: _free(p))
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=self.dir,
                             modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=instance)
        self.fmu.instantiate(callbacks=self._callbacks)
        self.states = {}

    def _keep(self, env, name, status, category, message):
        self.log.append((status, category.decode(), message.decode(errors="replace")))

    def call(self, op: str, *args):
        """One call of the script: set {name: value}, get [names], setup t0, enter, exit,
        step t h, getstate key, setstate key, serialize key, deserialize key, bytes key data,
        terminate, reset."""
        f = self.fmu
        actions = {
            "set": lambda values: self._set(values),
            "get": lambda names: self._get(names),
            "setup": lambda t0, *stop: f.setupExperiment(startTime=t0, stopTime=stop[0] if stop else None),
            "enter": f.enterInitializationMode,
            "exit": f.exitInitializationMode,
            "step": lambda t, h: f.doStep(currentCommunicationPoint=t, communicationStepSize=h),
            "getstate": lambda key: self.states.__setitem__(key, f.getFMUstate()),
            "setstate": lambda key: f.setFMUstate(self.states[key]),
            "serialize": lambda key: self.states.__setitem__(key, f.serializeFMUstate(self.states[key])),
            "deserialize": lambda key: self.states.__setitem__(key, f.deSerializeFMUstate(self.states[key])),
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

    def run(self, script) -> list[Step]:
        return [self.call(*item) for item in script]

    def close(self):
        self.fmu.freeInstance()
        if self._unzipped_here:
            shutil.rmtree(self.dir, ignore_errors=True)
