"""Worker process of :mod:`fmus.hostile.cases`: runs a batch of cases through fmpy.

Reads ``{"unzipped": {model: dir}, "cases": [...]}`` (JSON) from stdin and writes one JSON
line per case to the file descriptor ``$HOSTILE_RESULT_FD``: ``outcome``, ``statuses`` (the
FMI status of every call, by call), ``problems`` (the properties that failed) and
``seconds``.  After a case with fmi2Fatal it exits with status 3 (the instance may not be
freed, and the process is suspect); a crash ends it with the signal.
"""
from __future__ import annotations

import hashlib
import json
import math
import os
import pickle
import random
import signal
import struct
import sys
import tempfile
import time

from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave

from fmus.native.state_bytes import MAGIC as NATIVE_STATE_MAGIC
from fmus.native.state_bytes import fnv1a
from fmus.hostile.cases import CALL_LIMIT, EXIT_AFTER_FATAL, OK, REFUSED
from fmus.status import FMI_STATUS, FmiStatus, RunError, RunStatus, step_failed

#: Bytes of the checksum that ends a serialised parcosim state (docs/state.md).
CHECKSUM_BYTES = 32
#: Bytes of the checksum that ends a native FMU's state (issue 28: fmus/native/state_bytes.py).
NATIVE_CHECKSUM_BYTES = 8


class _Exploit:
    """Pickles to a call of os.system (the issue-30 exploit against a pickle-based state)."""

    def __init__(self, command: str):
        self.command = command

    def __reduce__(self):
        return os.system, (self.command,)

FATAL = FmiStatus.FATAL
NAMES = {s.value: "OK" if s is FmiStatus.OK else s.name.capitalize() for s in FmiStatus}
#: What a refused call may return (anything else but fmi2Fatal is a problem).
_ANSWERS = (FmiStatus.OK, FmiStatus.WARNING, FmiStatus.DISCARD, FmiStatus.ERROR)


class Fatal(Exception):
    """A call returned fmi2Fatal: the case ends there."""


class Runner:
    """One case on one FMU instance, recording every call's status."""

    def __init__(self, case: dict, unzip_dir: str, md, unzipped=None):
        self.case, self.md = case, md
        self.unzipped = unzipped or {}
        self.vars = {v.name: v for v in md.modelVariables}
        self.statuses, self.problems = [], []
        self.refused = False
        guid = md.guid if case.get("guid", "own") == "own" else "{00000000-0000-0000-0000-000000000000}"
        self.fmu = FMU2Slave(guid=guid, unzipDirectory=unzip_dir,
                             modelIdentifier=md.coSimulation.modelIdentifier,
                             instanceName=case["instance_name"])
        self.state = None

    def call(self, label: str, function, *args):
        """Call ``function``; record its status; raise Fatal on fmi2Fatal."""
        start = time.perf_counter()
        status = FmiStatus.OK
        result = None
        try:
            result = function(*args)
        except FMICallException as exc:
            status = exc.status
        seconds = time.perf_counter() - start
        if seconds > CALL_LIMIT:
            self.problems.append(f"{label} took {seconds:.1f} s (limit {CALL_LIMIT:g} s)")
        self.statuses.append([label, NAMES.get(status, str(status))])
        if status not in _ANSWERS:
            if status == FATAL:
                raise Fatal(label)
            self.problems.append(f"{label} returned status {status}")
        if step_failed(status):
            self.refused = True
            self.check_message(label, status)
        return status, result

    def check_message(self, label: str, status: int) -> None:
        """A refusal must leave a message in ``error`` naming something."""
        if "error" not in self.vars:
            return
        try:
            message = self.fmu.getString([self.vars["error"].valueReference])[0]
        except FMICallException as exc:
            self.problems.append(f"after the refused {label}: getString(error) returned status {exc.status}")
            return
        message = message.decode("utf-8", "replace") if isinstance(message, bytes) else str(message)
        if not label.startswith(("doStep", "exitInitializationMode")):   # the other calls refuse with
            return                                                          # fmi2Error and log the message
        names = [name for name in self.vars if name in message]
        if not message.strip() or not (names or " = " in message or "t = " in message):
            self.problems.append(f"the refused {label} left error = {message!r}, naming nothing")
        self.check_record(label, message, status)

    def check_record(self, label: str, message: str, status: int) -> None:
        """A refused step leaves its record in ``refusal`` (fmus.status.RunError): the instance's
        name, a kind of refusal and the message of ``error``; a refused doStep returns the status
        of that kind (fmus.status.FMI_STATUS)."""
        if "refusal" not in self.vars:
            return
        text = self.fmu.getString([self.vars["refusal"].valueReference])[0]
        try:
            record = RunError.from_json(text.decode("utf-8", "replace") if isinstance(text, bytes) else str(text))
        except (ValueError, TypeError) as exc:
            self.problems.append(f"the refused {label} left refusal = {text!r}, no record: {exc}")
            return
        if record is None or record.message != message or record.instance != self.case["instance_name"] or \
                record.kind not in (RunStatus.REFUSED, RunStatus.INITIALISATION):
            self.problems.append(f"the refused {label} left refusal = {text!r}, not the record of error = {message!r}")
        elif label.startswith("doStep") and status != FMI_STATUS[record.kind]:
            self.problems.append(f"the refused {label} returned {NAMES.get(status)}, not the "
                                 f"{NAMES[FMI_STATUS[record.kind]]} of a {record.kind.value} refusal")

    def set(self, name: str, value) -> None:
        v = self.vars[name]
        self.set_vr(v.type, v.valueReference, value, f"set {name}")

    def set_vr(self, type_: str, vr: int, value, label: str) -> None:
        f = self.fmu
        setter = {"Real": lambda: f.setReal([vr], [float(value)]),
                  "Integer": lambda: f.setInteger([vr], [int(value)]),
                  "Boolean": lambda: f.setBoolean([vr], [bool(value)]),
                  "String": lambda: f.setString([vr], [str(value)])}[type_]
        self.call(label, setter)

    def check_outputs(self, label: str) -> None:
        """After an fmi2OK step every Real output is finite."""
        outputs = [v for v in self.md.modelVariables if v.causality == "output" and v.type == "Real"]
        if not outputs:
            return
        status, values = self.call("get outputs", self.fmu.getReal, [v.valueReference for v in outputs])
        if status == FmiStatus.OK:
            bad = {v.name: x for v, x in zip(outputs, values) if not math.isfinite(x)}
            if bad:
                self.problems.append(f"non-finite outputs after the fmi2OK {label}: {bad}")

    def run(self) -> None:
        case, f = self.case, self.fmu
        if case.get("guid", "own") != "own":   # fmpy raises when fmi2Instantiate returns NULL
            try:
                f.instantiate(loggingOn=case["logging"])
            except Exception:  # noqa: BLE001 - fmpy's "Failed to instantiate model"
                self.statuses.append(["instantiate (another GUID)", "Error"])
                self.refused = True
            else:
                self.problems.append("fmi2Instantiate with a GUID that is not the FMU's returned an instance")
                self.call("freeInstance", f.freeInstance)
            return
        self.call("instantiate", lambda: f.instantiate(loggingOn=case["logging"]))
        start = case["start_time"]
        status, _ = self.call("setupExperiment", lambda: f.setupExperiment(startTime=start))
        unusable = not math.isfinite(start) or start + 1e-6 == start
        if unusable and status != 3:
            self.problems.append(f"setupExperiment({start!r}) returned {NAMES.get(status)}, not fmi2Error")
        if status != 0:
            start = 0.0
        self.call("enterInitializationMode", f.enterInitializationMode)
        for op in case["ops"]:
            if op[0] == "step_before_init":
                status, _ = self.call("doStep before initialisation", lambda: f.doStep(op[1], op[2]))
                if status == FmiStatus.OK:
                    self.problems.append("doStep before initialisation returned fmi2OK")
        for name, value in case["parameters"]:
            self.set(name, value)
        self.call("exitInitializationMode", f.exitInitializationMode)
        t, last = start, 0.0
        terminated, state_time = False, None
        for op in case["ops"]:
            kind = op[0]
            if kind == "set":
                self.set(op[1], op[2])
            elif kind == "set_vr":
                self.set_vr(op[1], op[2], op[3], f"set_vr {op[1]} {op[2]}")
            elif kind == "step":
                point = t + last if op[1] is None else op[1]
                h = op[2]
                label = f"doStep({point!r}, {h!r})"
                status, _ = self.call(label, lambda: f.doStep(point, h))
                if status == FmiStatus.OK:
                    self.check_outputs(label)
                    expected = t + last
                    if not (math.isfinite(h) and h > 0.0):
                        self.problems.append(f"{label} accepted a step size that is not finite and > 0")
                    if not abs(point - expected) <= 1e-9 * max(1e-3, abs(expected)):
                        self.problems.append(f"{label} accepted a communication point that does not follow "
                                             f"the last one ({expected!r})")
                    if terminated:
                        self.problems.append(f"{label} after fmi2Terminate returned fmi2OK")
                    t, last = point, h
            elif kind == "get":
                self.check_outputs("get")
            elif kind == "crash":       # the runner's own test: a case that kills the importer
                os.kill(os.getpid(), signal.SIGSEGV)
            elif kind == "terminate":
                self.call("terminate", f.terminate)
                terminated = True
            elif kind == "get_state" and not terminated:
                status, state = self.call("getFMUstate", f.getFMUState)
                if status == FmiStatus.OK:
                    self.state, state_time = state, t + last
            elif kind in ("exit_init_again", "enter_init_again", "setup_again"):
                call = {"exit_init_again": ("exitInitializationMode", f.exitInitializationMode),
                        "enter_init_again": ("enterInitializationMode", f.enterInitializationMode),
                        "setup_again": ("setupExperiment", lambda: f.setupExperiment(startTime=t + last))}[kind]
                status, _ = self.call(f"out of order: {call[0]}", call[1])   # FmiError: logged, 'error' untouched
                if status != 3:
                    self.problems.append(f"{call[0]} in Step Mode returned {NAMES.get(status)}, not fmi2Error")
            elif kind == "state_bytes" and not terminated:
                point = self.deserialize(op[1], op[2], op[3], t + last)
                if point is not None:
                    t, last = point, 0.0
            elif kind == "set_state" and self.state is not None and not terminated:
                status, _ = self.call("setFMUstate", lambda: f.setFMUState(self.state))
                if status == FmiStatus.OK:
                    t, last = state_time, 0.0
        if self.state is not None:
            self.call("freeFMUstate", lambda: f.freeFMUState(self.state))
        if not terminated:
            self.call("terminate", f.terminate)
        self.call("freeInstance", f.freeInstance)


    def state_bytes(self, variant: str, seed: int, other: str, marker: str) -> bytes:
        """Bytes of ``variant`` (fmus.hostile.cases.STATE_VARIANTS) for this FMU."""
        rng = random.Random(seed)
        if variant == "random":
            return bytes(rng.randrange(256) for _ in range(rng.randrange(1, 400)))
        if variant in ("exploit", "legacy"):
            payload = _Exploit(f"touch {marker}") if variant == "exploit" else {"x": 1.0}
            return b"parcosim-fmu-state-1\n" + self.case["model"].encode() + b"\n" + pickle.dumps(payload, protocol=4)
        if variant == "foreign":
            return self.foreign_state(other)
        status, state = self.call("getFMUstate (own)", self.fmu.getFMUState)
        if status != 0:
            return b""
        status, data = self.call("serializeFMUstate (own)", self.fmu.serializeFMUstate, state)
        self.call("freeFMUstate (own)", self.fmu.freeFMUState, state)
        data = bytes(data or b"")
        if not data:
            return data
        if variant == "truncated":
            return data[:rng.randrange(len(data))]
        if variant == "forged" and data.startswith(NATIVE_STATE_MAGIC):
            return forged_native_state(data, rng)
        altered = bytearray(data)
        altered[rng.randrange(len(data) - (CHECKSUM_BYTES if variant == "forged" else 0))] ^= rng.randrange(1, 256)
        if variant == "forged":
            body = bytes(altered[:-CHECKSUM_BYTES])
            return body + hashlib.sha256(body).digest()
        return bytes(altered)

    def foreign_state(self, other: str) -> bytes:
        """A serialised state of another FMU (``other``, initialised and stepped once)."""
        md = read_model_description(self.unzipped[other])
        fmu = FMU2Slave(guid=md.guid, unzipDirectory=self.unzipped[other],
                        modelIdentifier=md.coSimulation.modelIdentifier, instanceName="foreign")
        try:
            fmu.instantiate()
            fmu.setupExperiment(startTime=0.0)
            fmu.enterInitializationMode()
            fmu.exitInitializationMode()
            fmu.doStep(0.0, 1e-3)
            state = fmu.getFMUState()
            data = bytes(fmu.serializeFMUstate(state))
            fmu.freeFMUState(state)
            fmu.terminate()
            fmu.freeInstance()
            return data
        except FMICallException:
            return b""

    def deserialize(self, variant: str, seed: int, other: str, now: float):
        """Deserialise the bytes of ``variant`` and set them if taken; the time the FMU is at
        afterwards if it changed (a taken state's), else None."""
        with tempfile.TemporaryDirectory(prefix="hostile-") as folder:
            marker = os.path.join(folder, "code-ran")
            data = self.state_bytes(variant, seed, other, marker)
            label = f"deSerializeFMUstate ({variant})"
            status, state = self.call(label, self.fmu.deSerializeFMUstate, data)
            if os.path.exists(marker):
                self.problems.append(f"{label}: the state's bytes ran a command in the importer")
        if status == FmiStatus.OK and variant != "forged" and not (variant == "foreign" and other == self.case["model"]):
            self.problems.append(f"{label} returned fmi2OK for bytes that are not a state of this FMU")
        if status != 0:
            return None
        status, _ = self.call(f"setFMUstate ({variant})", self.fmu.setFMUState, state)
        self.call(f"freeFMUstate ({variant})", self.fmu.freeFMUState, state)
        return now if status == FmiStatus.OK else None


def forged_native_state(data: bytes, rng: random.Random) -> bytes:
    """A native state with one to three bytes altered and its checksum recomputed: only the
    FMU's checks of the fields (lengths, counts, flags, identifier) stand between the bytes
    and its memory."""
    body = bytearray(data[:-NATIVE_CHECKSUM_BYTES])
    for _ in range(rng.randint(1, 3)):
        body[rng.randrange(len(body))] ^= rng.randrange(1, 256)
    return bytes(body) + struct.pack("=Q", fnv1a(bytes(body)))


def main() -> int:
    job = json.loads(sys.stdin.read())
    out = os.fdopen(int(os.environ["HOSTILE_RESULT_FD"]), "w", buffering=1)
    descriptions = {}
    for case in job["cases"]:
        unzip_dir = job["unzipped"][case["model"]]
        md = descriptions.get(unzip_dir) or descriptions.setdefault(unzip_dir, read_model_description(unzip_dir))
        start = time.perf_counter()
        runner = Runner(case, unzip_dir, md, job["unzipped"])
        outcome = OK
        try:
            runner.run()
        except Fatal:
            outcome = "fatal"
        if outcome != "fatal":
            outcome = "violation" if runner.problems else (REFUSED if runner.refused else OK)
        out.write(json.dumps({"outcome": outcome, "statuses": runner.statuses, "problems": runner.problems,
                              "seconds": time.perf_counter() - start}) + "\n")
        out.flush()
        if outcome == "fatal":
            return EXIT_AFTER_FATAL
    return 0


if __name__ == "__main__":
    sys.exit(main())
