"""Run in a subprocess under AddressSanitizer and UBSan (tests/fmus/native/test_native_fmi3.py): drive one
unzipped FMI 3.0 native FMU through fmpy's raw FMI 3.0 functions with careless calls and
forged states; any memory error or undefined behaviour ends the process with the sanitizer's
exit status.  What FMI 3.0 adds to the FMI 2.0 campaign (tests/support/native_fuzz.py): the
types it has no variable of, nValues unlike nValueReferences, Boolean bytes other than 0 and 1,
NULL output pointers of fmi3DoStep, the independent variable, refused instantiations.
Usage: python native_fuzz3.py UNZIPPED_DIR SEED FMI2_STATE_FILE"""
from __future__ import annotations

import ctypes
import random
import struct
import sys
from pathlib import Path

from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import FMU3Slave, fmi3Boolean, fmi3Float64, fmi3ValueReference

from fmus.native.state_bytes import fnv1a, layout


def quiet(call, *args, **kwargs):
    try:
        return call(*args, **kwargs)
    except (FMICallException, Exception) as exc:   # fmpy raises plain Exception for a refused instantiation
        return exc


def with_checksum(data: bytearray) -> bytes:
    struct.pack_into("=Q", data, len(data) - 8, fnv1a(bytes(data[:-8])))
    return bytes(data)


def slave(md, folder, name="fuzz", **options) -> FMU3Slave:
    fmu = FMU3Slave(guid=md.guid, unzipDirectory=folder, modelIdentifier=md.coSimulation.modelIdentifier,
                    instanceName=name)
    fmu.instantiate(logMessage=lambda *message: None, **options)
    return fmu


def main(folder: str, seed: int, fmi2_state: bytes) -> None:
    rng = random.Random(seed)
    md = read_model_description(folder)
    refused = 0
    for options in ({"eventModeUsed": True}, {"requiredIntermediateVariables": [1, 2]}):
        refused += isinstance(quiet(slave, md, folder, **options), Exception)
    wrong = FMU3Slave(guid="not-this-token", unzipDirectory=folder, modelIdentifier=md.coSimulation.modelIdentifier,
                      instanceName="x")
    refused += isinstance(quiet(wrong.instantiate, logMessage=lambda *message: None), Exception)
    fmu = slave(md, folder)
    by_type = {}
    for v in md.modelVariables:
        by_type.setdefault(v.type, []).append(v.valueReference)
    everything = [v.valueReference for v in md.modelVariables] + [10_000, 2 ** 32 - 1]
    kinds = ("Float32", "Float64", "Int8", "UInt8", "Int16", "UInt16", "Int32", "UInt32", "Int64", "UInt64",
             "Boolean", "String", "Binary")
    for kind in kinds:                                   # every type at every reference: refused or read
        quiet(getattr(fmu, f"get{kind}"), everything)
        for vr in everything:
            quiet(getattr(fmu, f"get{kind}"), [vr])
    vrs = (fmi3ValueReference * 2)(*by_type["Float64"][:2])
    values = (fmi3Float64 * 8)()
    quiet(fmu.fmi3GetFloat64, fmu.component, vrs, 2, values, 8)          # nValues unlike nValueReferences
    quiet(fmu.fmi3SetFloat64, fmu.component, vrs, 2, values, 1)
    booleans = by_type.get("Boolean", [])
    if booleans:                                          # bytes 2 and 255 as Booleans: true, no UB
        raw = (ctypes.c_uint8 * len(booleans))(*[rng.choice((2, 255)) for _ in booleans])
        quiet(fmu.fmi3SetBoolean, fmu.component, (fmi3ValueReference * len(booleans))(*booleans), len(booleans),
              ctypes.cast(raw, ctypes.POINTER(fmi3Boolean)), len(booleans))
    quiet(fmu.doStep, 0.0, 1e-3)                          # before initialisation
    quiet(fmu.fmi3EnterEventMode, fmu.component)
    quiet(fmu.fmi3EnterStepMode, fmu.component)
    quiet(fmu.exitInitializationMode)
    fmu.enterInitializationMode(startTime=0.0)
    quiet(fmu.enterInitializationMode, startTime=0.0)
    fmu.exitInitializationMode()
    time_vr = next(v.valueReference for v in md.modelVariables if v.causality == "independent")
    quiet(fmu.setFloat64, [time_vr], [1.0])
    inputs = [v.valueReference for v in md.modelVariables if v.type == "Float64" and v.causality == "input"]
    nulls = [None, ctypes.byref(fmi3Boolean())]
    for k in range(30):
        quiet(fmu.setFloat64, inputs, [rng.uniform(-0.1, 0.1) for _ in inputs])
        if k % 10 == 9:                                   # an output pointer NULL: refused, nothing stepped
            quiet(fmu.fmi3DoStep, fmu.component, k * 1e-3, 1e-3, fmi3Boolean(True), nulls[k % 2], None, None, None)
        quiet(fmu.doStep, k * 1e-3, 1e-3)
    for kind, vrs in by_type.items():
        quiet(getattr(fmu, f"get{kind}"), vrs)
    state = fmu.getFMUState()
    good = fmu.serializeFMUState(state)
    forged = [good[:n] for n in range(len(good))] + [fmi2_state]
    for offset, form in layout(good)["sizes"]:            # each length or count near the bytes left, and huge
        limit = 256 ** struct.calcsize(form) - 1
        for value in [*range(40), *range(max(0, len(good) - offset - 40), len(good) - offset + 40), limit]:
            data = bytearray(good)
            struct.pack_into(form, data, offset, min(value, limit))
            forged.append(with_checksum(data) if offset != 12 else bytes(data))
    for _ in range(200):                                  # flips, checksum made right
        data = bytearray(good)
        for _ in range(rng.randrange(1, 4)):
            data[rng.randrange(len(data) - 8)] = rng.randrange(256)
        forged.append(with_checksum(data))
    accepted = 0
    for data in forged:
        restored = quiet(fmu.deserializeFMUState, data)
        if not isinstance(restored, Exception):
            accepted += 1
            quiet(fmu.setFMUState, restored)
            for kind, vrs in by_type.items():
                quiet(getattr(fmu, f"get{kind}"), vrs)
            quiet(fmu.doStep, 0.03, 1e-3)
            fmu.freeFMUState(restored)
    fmu.setFMUState(state)
    fmu.doStep(0.03, 1e-3)
    fmu.freeFMUState(state)
    fmu.terminate()
    quiet(fmu.doStep, 0.031, 1e-3)
    fmu.reset()
    fmu.freeInstance()
    print("survived", len(forged), "forged states,", accepted, "accepted;", refused, "of 3 instantiations refused")


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]), Path(sys.argv[3]).read_bytes())
