"""Raw FMI 2.0 calls through ctypes, for driving an FMU's binary with hostile arguments
(bytes that are not UTF-8, invalid value references, NULL arrays) that fmpy's checked
wrappers would not pass.  Used by tests/fmus/export/test_wrapper.py, always in a subprocess."""
from __future__ import annotations

import ctypes
from ctypes import (CFUNCTYPE, POINTER, Structure, byref, c_char, c_char_p, c_double, c_int, c_size_t, c_uint,
                    c_void_p)
from pathlib import Path
from xml.etree import ElementTree as ET

OK, WARNING, DISCARD, ERROR, FATAL, PENDING = range(6)

LOGGER = CFUNCTYPE(None, c_void_p, c_char_p, c_int, c_char_p, c_char_p)


class Callbacks(Structure):
    _fields_ = [("logger", LOGGER), ("allocateMemory", c_void_p), ("freeMemory", c_void_p),
                ("stepFinished", c_void_p), ("componentEnvironment", c_void_p)]


class RawFmu:
    """One unzipped FMU's binary; ``messages`` collects (status, category, format, text, instance name)."""

    def __init__(self, unzipped, logger: bool = True):
        unzipped = Path(unzipped)
        root = ET.parse(unzipped / "modelDescription.xml").getroot()
        self.guid = root.get("guid")
        self.identifier = root.find("CoSimulation").get("modelIdentifier")
        self.vars = {v.get("name"): (int(v.get("valueReference")), next(iter(v)).tag)
                     for v in root.find("ModelVariables")}
        self.dir = unzipped
        self.lib = ctypes.CDLL(str(unzipped / "binaries" / "linux64" / f"{self.identifier}.so"))
        self.messages = []
        # The variadic logger, read as logger(env, name, status, category, format): the
        # varargs are ignored, as fmpy does (our wrapper passes none).
        self._logger = LOGGER(self._log)
        self.callbacks = Callbacks(self._logger if logger else LOGGER(), None, None, None, None)
        lib = self.lib
        lib.fmi2Instantiate.restype = c_void_p
        lib.fmi2Instantiate.argtypes = [c_char_p, c_int, c_char_p, c_char_p, POINTER(Callbacks), c_int, c_int]
        for name in ("SetupExperiment", "EnterInitializationMode", "ExitInitializationMode", "Terminate", "Reset",
                     "DoStep", "SetReal", "GetReal", "SetString", "GetString", "SetInteger", "GetInteger",
                     "SetBoolean", "GetBoolean", "GetFMUstate", "SetFMUstate", "FreeFMUstate", "GetStatus",
                     "GetRealStatus", "GetDirectionalDerivative", "CancelStep", "SerializedFMUstateSize",
                     "SerializeFMUstate", "DeSerializeFMUstate"):
            getattr(lib, "fmi2" + name).restype = c_int
        lib.fmi2FreeInstance.restype = None
        lib.fmi2FreeInstance.argtypes = [c_void_p]
        lib.fmi2SetupExperiment.argtypes = [c_void_p, c_int, c_double, c_double, c_int, c_double]
        lib.fmi2DoStep.argtypes = [c_void_p, c_double, c_double, c_int]
        self.c = None

    def _log(self, env, name, status, category, fmt):
        self.messages.append((status, (category or b"").decode(errors="replace"), fmt,
                              (fmt or b"").decode(errors="replace").replace("%%", "%"), name))

    def text(self) -> str:
        """Every logged message (its format printed: '%%' -> '%'), one a line."""
        return "\n".join(m[3] for m in self.messages)

    def resource_uri(self) -> bytes:
        return ((self.dir / "resources").as_uri() + "/").encode()

    def instantiate(self, name=b"instance", uri: bytes | None = None, logging: bool = True):
        address = self.lib.fmi2Instantiate(name, 1, self.guid.encode(),
                                           uri if uri is not None else self.resource_uri(),
                                           byref(self.callbacks), 0, 1 if logging else 0)
        self.c = c_void_p(address) if address else None   # a pointer, not an int (truncated to 32 bits)
        return address

    def start(self, **strings) -> list[int]:
        """Set up, enter initialisation, set String parameters, exit; the statuses."""
        statuses = [self.lib.fmi2SetupExperiment(self.c, 0, 0.0, 0.0, 0, 0.0),
                    self.lib.fmi2EnterInitializationMode(self.c)]
        for name, value in strings.items():
            statuses.append(self.set_string(self.vars[name][0], value))
        statuses.append(self.lib.fmi2ExitInitializationMode(self.c))
        return statuses

    def step(self, t: float, h: float) -> int:
        return self.lib.fmi2DoStep(self.c, t, h, 1)

    def set_real(self, vr: int, value: float) -> int:
        return self.lib.fmi2SetReal(self.c, (c_uint * 1)(vr), c_size_t(1), (c_double * 1)(value))

    def get_real(self, vr: int):
        out = (c_double * 1)()
        status = self.lib.fmi2GetReal(self.c, (c_uint * 1)(vr), c_size_t(1), out)
        return status, out[0]

    def set_string(self, vr: int, value: bytes) -> int:
        return self.lib.fmi2SetString(self.c, (c_uint * 1)(vr), c_size_t(1), (c_char_p * 1)(value))

    def get_string(self, vr: int):
        out = (c_char_p * 1)()
        status = self.lib.fmi2GetString(self.c, (c_uint * 1)(vr), c_size_t(1), out)
        return status, out[0]

    def state_roundtrip(self):
        """Get a state, serialise it, deserialise it, set it, free both; the statuses."""
        state, again, size = c_void_p(), c_void_p(), c_size_t()
        lib = self.lib
        statuses = [lib.fmi2GetFMUstate(self.c, byref(state)),
                    lib.fmi2SerializedFMUstateSize(self.c, state, byref(size))]
        buffer = (c_char * size.value)()
        statuses += [lib.fmi2SerializeFMUstate(self.c, state, buffer, size),
                     lib.fmi2DeSerializeFMUstate(self.c, buffer, size, byref(again)),
                     lib.fmi2SetFMUstate(self.c, again),
                     lib.fmi2FreeFMUstate(self.c, byref(state)), lib.fmi2FreeFMUstate(self.c, byref(again))]
        return statuses

    def free(self):
        if self.c:
            self.lib.fmi2FreeInstance(self.c)
            self.c = None
