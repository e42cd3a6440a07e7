"""fmus/hostile/worker.py beyond the Runner's step checks (test_hostile_runner.py): the bytes it
hands fmi2DeSerializeFMUstate read back (the legacy and exploit states, the altered, forged and
truncated copies of a state, a native state forged with its checksum recomputed), its verdict on
each answer, its tolerance for rounded communication points far from t = 0, and the result lines
its ``main`` writes, read back exactly (issue 31: seed 3601's survivors [45], [79], [82], [165]
and [246], lines of the worker that only the slow campaign ran).  Made-up FMUs: fast."""
from __future__ import annotations

import hashlib
import io
import json
import os
import pickle
import pickletools
import random
import struct
import time
from types import SimpleNamespace

import pytest
from fmpy.fmi1 import FMICallException

from fmus.hostile import worker
from fmus.hostile.cases import EXIT_AFTER_FATAL, STATE_VARIANTS
from fmus.native.state_bytes import MAGIC as NATIVE_MAGIC
from fmus.status import FmiStatus
from tests.fmus.hostile.test_hostile_runner import VARIABLES, MadeUpFMU, _run

#: What the made-up FMU serialises as its own state (a parcosim state ends in a 32-byte checksum).
OWN_STATE = bytes(range(40)) + hashlib.sha256(bytes(range(40))).digest()


class StateFMU(MadeUpFMU):
    """A made-up FMU that serialises :data:`OWN_STATE`, and deserialises bytes by the rule
    ``accepts`` (bytes -> bool); a naive one (``unpickles``) loads what follows the legacy
    header with pickle, as parcosim's FMUs did before issue 30."""

    accepts = staticmethod(lambda data: False)
    unpickles = False

    def serializeFMUstate(self, state):
        return OWN_STATE

    def deSerializeFMUstate(self, data):
        data = bytes(data)
        if self.unpickles and data.startswith(b"parcosim-fmu-state-1\n"):
            pickle.loads(data.split(b"\n", 2)[2])
        if not self.accepts(data):
            raise FMICallException("fmi2DeSerializeFMUstate", int(FmiStatus.ERROR))
        return "decoded"

    def setFMUState(self, state):
        self.set_to = state


def _runner(monkeypatch, fmu=StateFMU, model="M", start_time=0.25):
    monkeypatch.setattr(worker, "FMU2Slave", fmu)
    md = SimpleNamespace(guid="{g}", coSimulation=SimpleNamespace(modelIdentifier=model), modelVariables=VARIABLES)
    monkeypatch.setattr(worker, "read_model_description", lambda path: md)
    case = {"model": model, "instance_name": "inst", "logging": False, "start_time": start_time, "ops": [],
            "parameters": []}
    return worker.Runner(case, "unused", md, {"M": "/u/m", "Other": "/u/other"})


# --- the bytes of each variant -------------------------------------------------------------------

def _globals_and_strings(data: bytes) -> tuple:
    """The opcodes and string arguments of a pickle, without loading it."""
    ops = [(op.name, arg) for op, arg, _ in pickletools.genops(data)]
    return [name for name, _ in ops], [arg for _, arg in ops if isinstance(arg, str)]


def test_the_legacy_and_exploit_states_are_the_old_header_and_a_pickle(monkeypatch, tmp_path):
    """The pre-issue-30 format: ``parcosim-fmu-state-1``, the model, then a pickle; the legacy
    pickle is plain data, the exploit's calls os.system on the marker command (read with
    pickletools, not run).  Catches the header's lines joined otherwise (seed 3601's [45]: the
    last newline subtracted) or the model left out."""
    runner = _runner(monkeypatch, model="FiveBarPlant")
    marker = str(tmp_path / "code-ran")
    for variant in ("legacy", "exploit"):
        data = runner.state_bytes(variant, 7, "", marker)
        magic, model, payload = data.split(b"\n", 2)
        assert (magic, model) == (b"parcosim-fmu-state-1", b"FiveBarPlant")
        names, strings = _globals_and_strings(payload)
        if variant == "legacy":
            assert pickle.loads(payload) == {"x": 1.0}
        else:
            assert "STACK_GLOBAL" in names and "REDUCE" in names
            assert strings[-3:] == [os.system.__module__, "system", f"touch {marker}"]
    assert not os.path.exists(marker)


def test_a_naive_fmu_that_unpickles_the_exploit_is_found_out(monkeypatch):
    """An FMU that loads the legacy format with pickle runs the exploit's command: the runner
    sees its marker and says so (and that it took bytes that are no state of it)."""
    runner = _runner(monkeypatch, fmu=type("Naive", (StateFMU,), {"unpickles": True}))
    assert runner.deserialize("exploit", 3, "", 0.5) is None
    assert runner.problems == ["deSerializeFMUstate (exploit): the state's bytes ran a command in the importer"]


@pytest.mark.parametrize("seed", range(12))
def test_altered_forged_and_truncated_copies_of_the_own_state(monkeypatch, seed):
    """Of the FMU's own serialised state: "truncated" a strict prefix, "altered" one byte
    changed anywhere, "forged" one byte of the body changed and its SHA-256 recomputed (only the
    FMU's own checks of the fields stand against it), "random" bytes of their own.  Catches
    the checksum recomputed over other bytes, a forged byte in the checksum, or no change."""
    runner = _runner(monkeypatch)
    truncated = runner.state_bytes("truncated", seed, "", "")
    assert len(truncated) < len(OWN_STATE) and OWN_STATE.startswith(truncated)
    altered = runner.state_bytes("altered", seed, "", "")
    assert len(altered) == len(OWN_STATE) and sum(a != b for a, b in zip(altered, OWN_STATE)) == 1
    forged = runner.state_bytes("forged", seed, "", "")
    body = forged[:-worker.CHECKSUM_BYTES]
    assert len(forged) == len(OWN_STATE) and forged[-worker.CHECKSUM_BYTES:] == hashlib.sha256(body).digest()
    assert sum(a != b for a, b in zip(body, OWN_STATE)) == 1
    random_bytes = runner.state_bytes("random", seed, "", "")
    assert random_bytes == runner.state_bytes("random", seed, "", "") and 1 <= len(random_bytes) < 400


def _fnv1a_64(data: bytes) -> int:
    """fmus/native/pcn_state.c's checksum, written here: 64-bit FNV-1a, offset basis
    14695981039346656037, prime 1099511628211."""
    h = 14695981039346656037
    for byte in data:
        h = ((h ^ byte) * 0x100000001B3) % 2 ** 64
    return h


@pytest.mark.parametrize("seed", range(12))
def test_a_forged_native_state_changes_up_to_three_bytes_and_carries_their_checksum(seed):
    """The native state's last 8 bytes are the FNV-1a of the rest in host order: the forged copy
    changes 1 to 3 bytes of the body and ends in the checksum of the changed body.  Catches the
    checksum's packing broken (seed 3601's [79]: its arguments swapped), taken over the old body,
    or the body unchanged."""
    rng = random.Random(100 + seed)
    body = NATIVE_MAGIC + bytes(rng.randrange(256) for _ in range(200))
    data = body + struct.pack("=Q", _fnv1a_64(body))
    forged = worker.forged_native_state(data, random.Random(seed))
    assert len(forged) == len(data)
    assert struct.unpack("=Q", forged[-8:])[0] == _fnv1a_64(forged[:-8])
    assert 1 <= sum(a != b for a, b in zip(forged[:-8], body)) <= 3


# --- the verdict on each answer --------------------------------------------------------------

@pytest.mark.parametrize("variant", STATE_VARIANTS)
def test_bytes_refused_are_no_problem_and_taken_only_forged_or_the_same_models(monkeypatch, variant):
    """Refused with fmi2Error, every variant is as it should be; taken, only a forged state
    (its checksum holds) and a state of another instance of the same model may be.  Catches
    the verdict's conditions joined by "or" (seed 3601's [165]: a refusal reported as taken) or
    one of its exceptions dropped."""
    refused = _runner(monkeypatch)
    assert refused.deserialize(variant, 5, "M", 0.5) is None
    assert refused.problems == [] and refused.statuses[-1] == [f"deSerializeFMUstate ({variant})", "Error"]
    for other in ("M", "Other"):
        taken = _runner(monkeypatch, fmu=type("Taking", (StateFMU,), {"accepts": staticmethod(lambda data: True)}))
        assert taken.deserialize(variant, 5, other, 0.5) == 0.5
        assert taken.fmu.set_to == "decoded"
        allowed = variant == "forged" or (variant == "foreign" and other == "M")
        assert taken.problems == ([] if allowed else [
            f"deSerializeFMUstate ({variant}) returned fmi2OK for bytes that are not a state of this FMU"])


# --- communication points far from 0 ---------------------------------------------------------

@pytest.mark.parametrize("start", [0.25, 1000.0, 3.0e5])
def test_a_point_off_by_rounding_is_no_problem_and_one_further_off_is(monkeypatch, start):
    """The runner accepts points within 1e-9 of max(1 ms, |t|) of the expected one, as the
    FMUs do: at t = 1000 s a point 0.8 us off is rounding, 1.25 us off is a point that does
    not follow.  Catches the tolerance made absolute (seed 3601's [82]: 1e-9 s, which reports
    every rounded point far from 0 as a problem) or relative to the step."""
    expected = start + 1e-3
    tolerance = 1e-9 * max(1e-3, expected)
    near = _run(monkeypatch, [["step", None, 1e-3], ["step", expected + 0.8 * tolerance, 1e-3]], start_time=start)
    assert near.problems == []
    far_point = expected + 1.25 * tolerance
    far = _run(monkeypatch, [["step", None, 1e-3], ["step", far_point, 1e-3]], start_time=start)
    assert far.problems == [f"doStep({far_point!r}, 0.001) accepted a communication point that does not follow "
                            f"the last one ({expected!r})"]


# --- the result lines ------------------------------------------------------------------------

class FatalFMU(MadeUpFMU):
    def doStep(self, point, h):
        raise FMICallException("doStep", int(FmiStatus.FATAL))


def test_main_writes_one_line_per_case_that_reads_back_as_the_runners_findings(monkeypatch, tmp_path):
    """Three cases (an ok one, one with a problem, one ending in fmi2Fatal) and one after the
    fatal: three JSON lines, each the case's outcome, every call's status, the problems and
    its seconds (>= 0, within the call), then exit status 3.  Catches a result line not
    written or written without its fields (seed 3601's [246]), the outcome misjudged, and a case
    run after fmi2Fatal."""
    fmus = {"ok": MadeUpFMU, "bad": MadeUpFMU, "fatal": FatalFMU}
    md = SimpleNamespace(guid="{g}", coSimulation=SimpleNamespace(modelIdentifier="M"), modelVariables=VARIABLES)
    monkeypatch.setattr(worker, "read_model_description", lambda path: md)
    monkeypatch.setattr(worker, "FMU2Slave", lambda **kwargs: fmus[kwargs["instanceName"]]())
    case = {"model": "M", "logging": False, "start_time": 0.0, "parameters": [["k", 2.0]]}
    cases = [{**case, "instance_name": "ok", "ops": [["step", None, 1e-3], ["get"]]},
             {**case, "instance_name": "bad", "ops": [["step", None, 1e-3], ["step", 0.5, 1e-3]]},
             {**case, "instance_name": "fatal", "ops": [["step", None, 1e-3]]},
             {**case, "instance_name": "ok", "ops": []}]
    monkeypatch.setattr("sys.stdin", io.StringIO(json.dumps({"unzipped": {"M": "/u/m"}, "cases": cases})))
    results = tmp_path / "results.jsonl"
    fd = os.open(results, os.O_WRONLY | os.O_CREAT)
    monkeypatch.setenv("HOSTILE_RESULT_FD", str(fd))
    start = time.perf_counter()
    assert worker.main() == EXIT_AFTER_FATAL
    elapsed = time.perf_counter() - start
    lines = [json.loads(line) for line in results.read_text().splitlines()]
    opening = [["instantiate", "OK"], ["setupExperiment", "OK"], ["enterInitializationMode", "OK"], ["set k", "OK"],
               ["exitInitializationMode", "OK"]]
    assert [set(line) for line in lines] == [{"outcome", "statuses", "problems", "seconds"}] * 3
    assert [line["outcome"] for line in lines] == ["ok", "violation", "fatal"]
    assert lines[0]["statuses"] == opening + [["doStep(0.0, 0.001)", "OK"], ["get outputs", "OK"],
                                              ["get outputs", "OK"], ["terminate", "OK"], ["freeInstance", "OK"]]
    assert lines[0]["problems"] == []
    assert lines[1]["problems"] == ["doStep(0.5, 0.001) accepted a communication point that does not follow the last "
                                    "one (0.001)"]
    assert lines[2]["statuses"] == opening + [["doStep(0.0, 0.001)", "Fatal"]] and lines[2]["problems"] == []
    assert all(0.0 <= line["seconds"] for line in lines) and sum(line["seconds"] for line in lines) <= elapsed
