"""Run in a subprocess under AddressSanitizer (tests/fmus/native/test_native_sanitized.py): drive one
unzipped native FMU through fmpy with careless calls and forged states; any memory error
ends the process with ASan's exit status.  A big state (a whole loop's, 200 kB) is cut at a
sample of places, and its forgeries checksummed in C (Python's fnv1a takes 0.17 s on it).
Usage: python native_fuzz.py UNZIPPED_DIR SEED [INPUTS.json]
(INPUTS.json: 30 rows {input name: value} for the steps, in place of random inputs)."""
from __future__ import annotations

import ctypes
import json
import random
import struct
import subprocess
import sys
import tempfile
from pathlib import Path

from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave

from fmus.native.state_bytes import fnv1a, layout

#: A state longer than this (bytes) is cut at its first BIG bytes, its last 512 and 200 places between.
BIG = 4096


def quiet(call, *args):
    try:
        return call(*args)
    except FMICallException:
        return None


#: The state's checksum in C: Python's fnv1a takes 0.17 s on a whole loop's 200 kB state.
FNV_C = ("unsigned long long fnv(const unsigned char *p, unsigned long n) {\n"
         "    unsigned long long h = 0xcbf29ce484222325ULL;\n"
         "    for (unsigned long i = 0; i < n; ++i) { h ^= p[i]; h *= 1099511628211ULL; }\n"
         "    return h;\n}\n")


def fast_fnv1a():
    """``fnv1a`` compiled (cc), checked against Python's on a sample."""
    folder = Path(tempfile.mkdtemp(prefix="fnv_"))
    (folder / "fnv.c").write_text(FNV_C)
    subprocess.run(["cc", "-O2", "-shared", "-fPIC", str(folder / "fnv.c"), "-o", str(folder / "fnv.so")], check=True)
    lib = ctypes.CDLL(str(folder / "fnv.so"))
    lib.fnv.restype, lib.fnv.argtypes = ctypes.c_ulonglong, [ctypes.c_char_p, ctypes.c_ulong]
    checksum = lambda data: lib.fnv(bytes(data), len(data))   # noqa: E731
    sample = bytes(range(256)) * 3
    assert checksum(sample) == fnv1a(sample)
    return checksum


CHECKSUM = fnv1a


def with_checksum(data: bytearray) -> bytes:
    struct.pack_into("=Q", data, len(data) - 8, CHECKSUM(bytes(data[:-8])))
    return bytes(data)


def main(folder: str, seed: int, rows=None) -> None:
    rng = random.Random(seed)
    md = read_model_description(folder)
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=folder, modelIdentifier=md.coSimulation.modelIdentifier,
                    instanceName="fuzz")
    fmu.instantiate()
    by_type = {}
    for v in md.modelVariables:
        by_type.setdefault(v.type, []).append(v.valueReference)
    everything = [v.valueReference for v in md.modelVariables] + [10_000, 2 ** 32 - 1]
    for kind in ("Real", "Integer", "Boolean", "String"):   # every type at every reference: refused or read
        quiet(getattr(fmu, f"get{kind}"), everything)
    quiet(fmu.doStep, 0.0, 1e-3)                             # before initialisation
    strings = [v.valueReference for v in md.modelVariables if v.type == "String" and v.causality == "parameter"]
    long_text = "%s%n" * 2000                                 # messages cut at their buffer's end, no format read
    for vr in strings:                                        # an instance that refuses its initialisation
        other = FMU2Slave(guid=md.guid, unzipDirectory=folder, modelIdentifier=md.coSimulation.modelIdentifier,
                          instanceName="long" * 500)
        other.instantiate()
        other.setString([vr], [long_text])
        other.setupExperiment(startTime=0.0)
        other.enterInitializationMode()
        quiet(other.getReal, by_type.get("Real", []))
        other.exitInitializationMode()
        quiet(other.doStep, 0.0, 1e-3)
        quiet(other.getString, by_type["String"])
        other.freeInstance()
    quiet(fmu.exitInitializationMode)
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    quiet(fmu.setupExperiment, 0.0)
    fmu.exitInitializationMode()
    inputs = [v for v in md.modelVariables if v.type == "Real" and v.causality == "input"]
    reals = [v.valueReference for v in inputs]
    accepted = 0
    for k in range(30):
        row = rows[k] if rows else {v.name: rng.uniform(-0.1, 0.1) for v in inputs}
        quiet(fmu.setReal, reals, [row[v.name] for v in inputs])
        try:
            fmu.doStep(k * 1e-3, 1e-3)
            accepted += 1
        except FMICallException:
            pass
    for kind, vrs in by_type.items():
        quiet(getattr(fmu, f"get{kind}"), vrs)
    quiet(fmu.setString, strings, [long_text] * len(strings))   # refused after initialisation, named
    state = fmu.getFMUstate()
    good = fmu.serializeFMUstate(state)
    big = len(good) > BIG           # a whole loop's state: its header, its end and a sample between
    if big:
        global CHECKSUM
        CHECKSUM = fast_fnv1a()
    cuts = sorted({*range(BIG), *range(len(good) - 512, len(good)), *rng.sample(range(len(good)), 200)}) if big \
        else range(len(good))
    forged = [good[:n] for n in cuts]                                       # every truncation (or that sample)
    forged += [good + bytes(rng.randrange(256) for _ in range(rng.randrange(1, 64)))]
    near = 8 if big else 80
    for offset, form in layout(good)["sizes"]:      # each length or count near the bytes left, and huge
        limit = 256 ** struct.calcsize(form) - 1
        for value in [*range(near), *range(max(near, len(good) - offset - near), len(good) - offset + near), limit,
                      limit // 2 + 1]:
            data = bytearray(good)
            struct.pack_into(form, data, offset, min(value, limit))
            forged.append(with_checksum(data) if offset != 12 else bytes(data))
    for _ in range(300):                                    # flips, checksum made right
        data = bytearray(good)
        for _ in range(rng.randrange(1, 4)):
            data[rng.randrange(len(data) - 8)] = rng.randrange(256)
        forged.append(with_checksum(data))
    for data in forged:
        restored = quiet(fmu.deSerializeFMUstate, data)
        if restored is not None:
            quiet(fmu.setFMUstate, restored)
            for kind, vrs in by_type.items():
                quiet(getattr(fmu, f"get{kind}"), vrs)
            quiet(fmu.doStep, 0.03, 1e-3)
            fmu.freeFMUstate(restored)
    fmu.setFMUstate(state)
    quiet(fmu.doStep, 0.03, 1e-3)
    fmu.freeFMUstate(state)
    fmu.terminate()
    quiet(fmu.doStep, 0.031, 1e-3)
    fmu.reset()
    fmu.freeInstance()
    print("survived", len(forged), "forged states;", accepted, "of 30 steps accepted")


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]), json.loads(Path(sys.argv[3]).read_text()) if len(sys.argv) > 3 else None)
