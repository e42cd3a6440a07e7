"""Worker process of :mod:`scenarios.hostile`: runs a batch of cases through fmpy.

Reads ``{"unzipped": {model: dir}, "cases": [...]}`` (JSON) from stdin and writes one JSON
line per case to the file descriptor ``$HOSTILE_RESULT_FD``: ``outcome``, ``statuses`` (the
FMI status of every call, by call), ``problems`` (the properties that failed) and
``seconds``.  After a case with fmi2Fatal it exits with status 3 (the instance may not be
freed, and the process is suspect); a crash ends it with the signal.
"""
from __future__ import annotations

import json
import math
import os
import signal
import sys
import time

from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave

from scenarios.hostile import CALL_LIMIT

FATAL = 4
NAMES = {0: "OK", 1: "Warning", 2: "Discard", 3: "Error", 4: "Fatal", 5: "Pending"}


class Fatal(Exception):
    """A call returned fmi2Fatal: the case ends there."""


class Runner:
    """One case on one FMU instance, recording every call's status."""

    def __init__(self, case: dict, unzip_dir: str, md):
        self.case, self.md = case, md
        self.vars = {v.name: v for v in md.modelVariables}
        self.statuses, self.problems = [], []
        self.refused = False
        self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzip_dir,
                             modelIdentifier=md.coSimulation.modelIdentifier,
                             instanceName=case["instance_name"])
        self.state = None

    def call(self, label: str, function, *args):
        """Call ``function``; record its status; raise Fatal on fmi2Fatal."""
        start = time.perf_counter()
        status = 0
        result = None
        try:
            result = function(*args)
        except FMICallException as exc:
            status = exc.status
        seconds = time.perf_counter() - start
        if seconds > CALL_LIMIT:
            self.problems.append(f"{label} took {seconds:.1f} s (limit {CALL_LIMIT:g} s)")
        self.statuses.append([label, NAMES.get(status, str(status))])
        if status not in (0, 1, 2, 3):
            if status == FATAL:
                raise Fatal(label)
            self.problems.append(f"{label} returned status {status}")
        if status in (2, 3):
            self.refused = True
            self.check_message(label)
        return status, result

    def check_message(self, label: str) -> None:
        """A refusal must leave a message in ``error`` naming something."""
        if "error" not in self.vars:
            return
        try:
            message = self.fmu.getString([self.vars["error"].valueReference])[0]
        except FMICallException as exc:
            self.problems.append(f"after the refused {label}: getString(error) returned status {exc.status}")
            return
        message = message.decode("utf-8", "replace") if isinstance(message, bytes) else str(message)
        if label.startswith(("set", "get")):      # refused sets and gets raise: the message is the log's
            return
        names = [name for name in self.vars if name in message]
        if not message.strip() or not (names or " = " in message or "t = " in message):
            self.problems.append(f"the refused {label} left error = {message!r}, naming nothing")

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
        if status == 0:
            bad = {v.name: x for v, x in zip(outputs, values) if not math.isfinite(x)}
            if bad:
                self.problems.append(f"non-finite outputs after the fmi2OK {label}: {bad}")

    def run(self) -> None:
        case, f = self.case, self.fmu
        self.call("instantiate", lambda: f.instantiate(loggingOn=case["logging"]))
        self.call("setupExperiment", lambda: f.setupExperiment(startTime=case["start_time"]))
        self.call("enterInitializationMode", f.enterInitializationMode)
        for op in case["ops"]:
            if op[0] == "step_before_init":
                status, _ = self.call("doStep before initialisation", lambda: f.doStep(op[1], op[2]))
                if status == 0:
                    self.problems.append("doStep before initialisation returned fmi2OK")
        for name, value in case["parameters"]:
            self.set(name, value)
        self.call("exitInitializationMode", f.exitInitializationMode)
        t, last = case["start_time"], 0.0
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
                if status == 0:
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
                if status == 0:
                    self.state, state_time = state, t + last
            elif kind == "set_state" and self.state is not None and not terminated:
                status, _ = self.call("setFMUstate", lambda: f.setFMUState(self.state))
                if status == 0:
                    t, last = state_time, 0.0
        if self.state is not None:
            self.call("freeFMUstate", lambda: f.freeFMUState(self.state))
        if not terminated:
            self.call("terminate", f.terminate)
        self.call("freeInstance", f.freeInstance)


def main() -> int:
    job = json.loads(sys.stdin.read())
    out = os.fdopen(int(os.environ["HOSTILE_RESULT_FD"]), "w", buffering=1)
    descriptions = {}
    for case in job["cases"]:
        unzip_dir = job["unzipped"][case["model"]]
        md = descriptions.get(unzip_dir) or descriptions.setdefault(unzip_dir, read_model_description(unzip_dir))
        start = time.perf_counter()
        runner = Runner(case, unzip_dir, md)
        outcome = "ok"
        try:
            runner.run()
        except Fatal:
            outcome = "fatal"
        if outcome != "fatal":
            outcome = "violation" if runner.problems else ("refused" if runner.refused else "ok")
        out.write(json.dumps({"outcome": outcome, "statuses": runner.statuses, "problems": runner.problems,
                              "seconds": time.perf_counter() - start}) + "\n")
        out.flush()
        if outcome == "fatal":
            return 3
    return 0


if __name__ == "__main__":
    sys.exit(main())
