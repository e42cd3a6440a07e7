"""The hostile-use campaign against FMUs built with AddressSanitizer and
UndefinedBehaviorSanitizer (issue 28, item 5).

Cases come from :func:`fmus.hostile.cases.make_case` and run in worker subprocesses with the
ASan runtime preloaded (:func:`fmus.hostile.cases.sanitizer_env`): an out-of-bounds access,
a use after free or undefined behaviour in an FMU ends its worker, and the case is a crash.
First the harness itself: the C low-pass of benchmarks/baseline_fmu with its instance
allocated 8 bytes short is a crash in every case, and is clean when allocated right.
"""
from __future__ import annotations

import subprocess
import zipfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from fmus.hostile import cases as hostile

pytestmark = [pytest.mark.fmu, pytest.mark.tools]

#: Links into the low-pass a calloc that returns 8 bytes whatever is asked: its instance
#: is written past its end in fmi2Instantiate.
SHORT_CALLOC = """#include <stddef.h>
void *__real_calloc(size_t n, size_t size);
void *__wrap_calloc(size_t n, size_t size) { (void)n; (void)size; return __real_calloc(1, 8); }
"""


def _sanitizer_env_or_skip(log_dir):
    try:
        return hostile.sanitizer_env(log_dir)
    except Exception as exc:  # noqa: BLE001 - no compiler, no runtime
        pytest.skip(f"no AddressSanitizer runtime here: {exc}")


def sanitized_lowpass(out: Path, short_allocation: bool) -> Path:
    """The low-pass FMU built with the kernels' sanitizer flags (kernels.build.SANITIZE)."""
    import fmpy

    from benchmarks.cold_start import BASELINE_DIR
    from kernels import build

    headers = Path(fmpy.__file__).resolve().parent / "c-code"
    sources = [str(BASELINE_DIR / "lowpass.c")]
    if short_allocation:
        (out / "short_calloc.c").write_text(SHORT_CALLOC)
        sources += [str(out / "short_calloc.c"), "-Wl,--wrap=calloc"]
    library = out / "lowpass.so"
    subprocess.run([build.compiler(), "-std=c11", "-fPIC", "-shared", *build.SANITIZE, f"-I{headers}", *sources,
                    "-o", str(library), "-lm"], check=True, capture_output=True)
    path = out / "LowPass.fmu"
    with zipfile.ZipFile(path, "w") as z:
        z.write(BASELINE_DIR / "modelDescription.xml", "modelDescription.xml")
        z.write(library, "binaries/linux64/lowpass.so")
    return path


def sane_lowpass_case(seed: int) -> dict:
    """A case of plain use (the baseline low-pass is no hardened FMU: under hostile cases it
    gives NaN with fmi2OK, and its log calls read the instance name fmpy freed, which FMI 2.0
    requires an FMU to copy; docs/extremes.md)."""
    ops = [op for k in range(3) for op in (["set", "u", 1.0 + k], ["step", None, 1e-3], ["get"])]
    return {"model": "LowPass", "kind": "inputs", "seed": seed, "instance_name": "instance", "logging": True,
            "start_time": 0.0, "guid": "own", "parameters": [["tau", 0.02]], "ops": ops}


@pytest.mark.parametrize("short_allocation", (False, True))
def test_the_sanitized_campaign_sees_an_fmu_write_past_its_allocation(tmp_path, short_allocation):
    """Catches a sanitized hostile campaign that misses a heap overflow in an FMU (reports it as ok), or
    flags a sound FMU."""
    env = _sanitizer_env_or_skip(tmp_path / "logs")
    fmu = sanitized_lowpass(tmp_path, short_allocation)
    unzipped = hostile.extract_fmus({"LowPass": fmu}, tmp_path / "fmus")
    results = hostile.run_cases([sane_lowpass_case(seed) for seed in range(4)], unzipped, env=env)
    reports = sorted((tmp_path / "logs").glob("asan.*"))
    if short_allocation:
        assert [r.outcome for r in results] == ["crash"] * 4
        assert all(f"exit status {hostile.ASAN_EXIT}" in r.problems[0] for r in results)
        assert "heap-buffer-overflow" in reports[0].read_text()
    else:
        assert [r.outcome for r in results] == ["ok"] * 4 and not reports


# --- the native FMUs (fmus.native: parcosim build --native) ------------------------------------

from fmus.native.models import NATIVE

CASES_PER_FMU = 9            # every kind once
SEED = 280                   # fixed: CI runs the same cases every time


@pytest.fixture(scope="module")
def native_sanitized(native_fmus, tmp_path_factory):
    """Model -> its native FMU rebuilt from its own sources with the sanitizers, extracted."""
    work = tmp_path_factory.mktemp("native")
    _sanitizer_env_or_skip(None)
    with ThreadPoolExecutor(max_workers=2) as pool:       # the compiler runs outside the GIL
        sanitized = dict(zip(native_fmus, pool.map(lambda p: hostile.sanitized_from_sources(p, work / "sanitized"),
                                                   native_fmus.values())))
    return hostile.extract_fmus(sanitized, work / "fmus")


def failures(results) -> list:
    return [f"{r.outcome}: {r.problems} -- {r.case['kind']} seed {r.case['seed']} -- last calls {r.statuses[-4:]}"
            for r in results if r.outcome not in ("ok", "refused") or r.problems]


def state_cases(model: str, unzipped: dict) -> list:
    """One "state" case per variant of :data:`fmus.hostile.cases.STATE_VARIANTS`, forged twice
    more; "foreign" bytes are another native model's when there is one."""
    others = [m for m in unzipped if m != model] or [model]
    base = hostile.cases_for(model, unzipped[model], range(SEED, SEED + 3), wrapper=True, kinds=["state"])
    cases = []
    for i, variant in enumerate(hostile.STATE_VARIANTS + ("forged", "forged")):
        case = json_copy(base[i % len(base)])
        case["seed"] = SEED + 100 + i
        case["ops"] = [["state_bytes", variant, SEED + i, others[i % len(others)]] if op[0] == "state_bytes" else op
                       for op in case["ops"]]
        cases.append(case)
    return cases


@pytest.fixture(scope="module")
def loop_sanitized(native_loop_fmu, tmp_path_factory):
    """The native ClosedLoop (``export-fmu --native``) and, for another model's state bytes,
    the native Derivator, each rebuilt from its own sources with the sanitizers, extracted."""
    from fmus.native.build import build_native_fmu

    work = tmp_path_factory.mktemp("loop")
    _sanitizer_env_or_skip(None)
    fmus = {"ClosedLoop": native_loop_fmu, "Derivator": build_native_fmu("Derivator", work / "native")}
    with ThreadPoolExecutor(max_workers=2) as pool:
        sanitized = dict(zip(fmus, pool.map(lambda p: hostile.sanitized_from_sources(p, work / "sanitized"),
                                            fmus.values())))
    return hostile.extract_fmus(sanitized, work / "fmus")


@pytest.mark.parametrize("model", list(NATIVE))
def test_native_fmu_under_hostile_use_and_sanitizers(model, native_sanitized, tmp_path):
    """No crash (ASan, UBSan), no hang, no fmi2Fatal, no NaN with fmi2OK, every refusal with
    a message: every kind of case, the strict ones (sets FMI refuses, state bytes, start
    times, call orders) included; then each kind of state bytes: random, truncated, altered
    (checksum left wrong), pickled (the issue-30 exploit, a legacy state), another model's:
    fmi2Error, no command run; forged (checksum recomputed): refused or, if taken, the steps
    after it clean.  One worker process for all the cases of a model."""
    campaign(model, native_sanitized, tmp_path)


def test_native_closed_loop_under_hostile_use_and_sanitizers(loop_sanitized, tmp_path):
    """The same campaign against a scene's whole loop as one native FMU (bench_circle_TCMDx:
    eight members' kernels, a 26 042-word data arena in its state)."""
    campaign("ClosedLoop", loop_sanitized, tmp_path)


def campaign(model: str, native_sanitized: dict, tmp_path) -> None:
    """Every kind of case, then every state variant, against ``model`` (the tests above)."""
    assert hostile.is_native(native_sanitized[model])
    cases = hostile.cases_for(model, native_sanitized[model], range(SEED, SEED + CASES_PER_FMU), wrapper=True,
                              kinds=list(hostile.KINDS))
    states = state_cases(model, native_sanitized)
    results = hostile.run_cases(cases + states, native_sanitized, batch=len(cases + states),
                                env=hostile.sanitizer_env(tmp_path / "logs"))
    reports = [p.read_text()[:1500] for p in (tmp_path / "logs").glob("*san.*")]
    assert not failures(results) and not reports, "\n".join(failures(results) + reports)
    assert {r.case["kind"] for r in results} == set(hostile.KINDS)
    assert all(any(s[1] == "Error" for s in r.statuses) for r in results
               if r.case["kind"] == "sets" and any(op[0] == "set_vr" for op in r.case["ops"]))
    own_model_only = len(native_sanitized) == 1
    for r in results[len(cases):]:
        variant = next(op[1] for op in r.case["ops"] if op[0] == "state_bytes")
        statuses = [s[1] for s in r.statuses if s[0].startswith("deSerializeFMUstate")]
        if variant == "forged":
            assert statuses in (["Error"], ["OK"]), r.statuses
        elif variant != "foreign" or not own_model_only:
            assert statuses == ["Error"], (variant, r.statuses)


def json_copy(value):
    import json

    return json.loads(json.dumps(value))


#: Prints (hex) the serialised state of an FMU just initialised: argv unzip dir, GUID, identifier.
SERIALISE = """import sys
from fmpy.fmi2 import FMU2Slave
slave = FMU2Slave(guid=sys.argv[2], unzipDirectory=sys.argv[1], modelIdentifier=sys.argv[3], instanceName="forger")
slave.instantiate(); slave.setupExperiment(startTime=0.0)
slave.enterInitializationMode(); slave.exitInitializationMode()
sys.stdout.write(bytes(slave.serializeFMUstate(slave.getFMUState())).hex())
"""


@pytest.mark.parametrize("model", list(NATIVE)[:1])
def test_the_forger_writes_the_checksum_a_native_state_carries(model, native_sanitized):
    """Forged states are only worth their name if their checksum passes: the worker's
    checksum of a real state's bytes must be the one the state ends with.  (The sanitized
    binary loads only with the ASan runtime first: a child process.)"""
    import os
    import struct
    import sys

    from fmpy import read_model_description

    from fmus.hostile.worker import NATIVE_CHECKSUM_BYTES, NATIVE_STATE_MAGIC, fnv1a

    unzip_dir = str(native_sanitized[model])
    md = read_model_description(unzip_dir)
    run = subprocess.run([sys.executable, "-c", SERIALISE, unzip_dir, md.guid, md.coSimulation.modelIdentifier],
                         capture_output=True, text=True, env={**os.environ, **hostile.sanitizer_env(None)}, check=True)
    data = bytes.fromhex(run.stdout)
    assert data.startswith(NATIVE_STATE_MAGIC)
    body, checksum = data[:-NATIVE_CHECKSUM_BYTES], data[-NATIVE_CHECKSUM_BYTES:]
    assert struct.unpack("=Q", checksum)[0] == fnv1a(body)
