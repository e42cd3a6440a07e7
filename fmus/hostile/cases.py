"""Hostile and careless use of the FMUs: the case generator and the batch runner (issue 13).

A *case* is one FMU instance driven through fmpy with random parameters, inputs, step
sizes, call orders and strings (:func:`make_case`, from a seed: the same seed gives the
same case).  Cases run in worker subprocesses (:mod:`fmus.hostile.worker`), a batch
per worker, so that a crash of the importing process is an outcome, not the end of the
run: :func:`run_cases` starts a new worker after a crash, a hang (a case over
:data:`CASE_TIMEOUT`) or an fmi2Fatal.

The worker checks the properties of docs/extremes.md ("The FMI calls under hostile use")
and reports each case's outcome:

* ``ok``: every call returned fmi2OK (or fmi2Warning);
* ``refused``: some call returned fmi2Discard or fmi2Error, with a message in ``error``;
* ``fatal``: a call returned fmi2Fatal;
* ``violation``: a property failed (a non-finite output after fmi2OK, a refusal without a
  message, a call over :data:`CALL_LIMIT` seconds);
* ``crash``: the worker process died; ``hang``: the case took over :data:`CASE_TIMEOUT`.

``tests/fmus/hostile/test_hostile.py`` runs 30 derandomised cases per FMU; ``python -m
fmus.hostile.campaign --cases 3000`` the long campaign.
"""
from __future__ import annotations

import json
import math
import os
import random
import select
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from fmus.status import RunStatus

#: Longest an FMI call may take [s].
CALL_LIMIT = 10.0
#: A case taking longer (all its calls) is a hang.
CASE_TIMEOUT = 60.0
#: What each case mostly exercises.
KINDS = ("parameters", "inputs", "steps", "order", "strings", "sets", "state", "start", "lifecycle")
#: Kinds whose calls FMI 2.0 wants refused with fmi2Error (a set of an output, of a fixed
#: parameter after initialisation, an unknown or wrongly typed value reference; bytes that
#: are not a state of this FMU; a start time that is not finite): pythonfmu's own binary
#: returns fmi2Fatal there; checked only when the FMU's binary is parcosim's wrapper
#: (:data:`fmus.slave.base.WRAPPER_SYMBOL`).
WRAPPER_KINDS = ("sets", "state", "start", "lifecycle")
#: A case's outcomes, in the order of the summary table: the FMU answered every call as FMI
#: allows (``ok``) or refused one so (``refused``: :class:`fmus.status.RunStatus`'s word); the
#: others (fmi2Fatal, a broken rule, a dead or hung worker) are findings.
OK, REFUSED = "ok", RunStatus.REFUSED.value
OUTCOMES = (OK, REFUSED, "fatal", "violation", "crash", "hang")
#: The outcomes that are no finding.
ANSWERED = (OK, REFUSED)
#: The worker's exit status after a case whose call returned fmi2Fatal (its instance may not be
#: called again): the case is ``fatal``, not a ``crash``.
EXIT_AFTER_FATAL = 3

DBL_MAX = sys.float_info.max
HOSTILE_REALS = (0.0, -0.0, 1.0, -1.0, 1e-300, -1e-300, 5e-324, -5e-324, 1e300, -1e300, DBL_MAX, -DBL_MAX,
                 math.nan, math.inf, -math.inf, 1e-12, 1e6, 1e7)
HOSTILE_INTEGERS = (0, -1, 1, 2, -2 ** 31, 2 ** 31 - 1, 10000, 10001, 100)
HOSTILE_STRINGS = ("", "nonsense", "%s", "%s%s%s%s%n", "%d%x%p", "é", "日本", "a" * 2000, "\t\n", "#%41%20",
                   "None", "-1", "current", "voltage", "exact", "tabulated", "hold", "circle", "dynamic")
#: Input values the generator varies around (the FMUs' start values elsewhere): a pose
#: the controller's kinematics accept (the bench's x1).
SANE_INPUTS = {"PositionController": {"q1": 0.5590695686115272, "q2": 2.625626722466347, "x_d": -0.002,
                                      "y_d": 0.108}}
STEP_SIZES = (1e-3, 1e-3, 1e-3, 5e-4, 2.5e-4, 2e-3, 1e-2, 0.5, 10.0, 0.0, -1e-3, math.nan, math.inf, 1e300,
              5e-324, 1e-9, 1e-10, 3e-4, 1e9, 100.0)
#: Serialised states a "state" case gives fmi2DeSerializeFMUstate (fmus.hostile.worker
#: makes the bytes): all but "forged" must be refused; "forged" (a byte altered, the
#: checksum recomputed) may be taken, and the steps after it must then stay clean.
STATE_VARIANTS = ("random", "exploit", "truncated", "altered", "forged", "foreign", "legacy")
#: Calls of a "lifecycle" case out of FMI 2.0's order, each to be refused with fmi2Error and
#: nothing changed; "guid" instantiates with a GUID that is not the FMU's (refused: NULL).
LIFECYCLE_CALLS = ("exit_init_again", "enter_init_again", "setup_again", "guid")
#: Start times of a "start" case: those that are not finite or where t0 + 1e-6 == t0 must be
#: refused by fmi2SetupExperiment (fmi2Error).
START_TIMES = (0.0, -1.0, 1e5, 1e9, 1e10, 1e17, -1e20, 1e-300, math.inf, -math.inf, math.nan)


def variable_table(model_description) -> list:
    """[(name, type, causality, variability, start)] of an fmpy model description."""
    table = []
    for v in model_description.modelVariables:
        start = v.start
        if start is not None:
            start = {"Real": float, "Integer": int, "Boolean": lambda s: str(s).lower() in ("true", "1"),
                     "String": str}[v.type](start)
        table.append((v.name, v.type, v.causality, v.variability, start))
    return table


def _value(rng: random.Random, kind: str, start, hostile: float, spread: float = 0.5):
    """A value of FMI type ``kind``: within ``spread`` (relative) of ``start`` mostly, hostile
    with probability ``hostile``."""
    if kind == "Boolean":
        return rng.random() < 0.5
    if kind == "String":
        return rng.choice(HOSTILE_STRINGS) if rng.random() < hostile else (start or "")
    if kind == "Integer":
        if rng.random() < hostile:
            return rng.choice(HOSTILE_INTEGERS)
        return int(start or 0) + rng.randint(-2, 2)
    if rng.random() < hostile:
        return rng.choice(HOSTILE_REALS)
    base = float(start) if start is not None and math.isfinite(float(start)) else 0.0
    return base * rng.uniform(1.0 - spread, 1.0 + spread) + rng.uniform(-0.01, 0.01) * spread * (abs(base) or 1.0)


def make_case(model: str, variables: list, seed: int, kind: str | None = None, wrapper: bool = False,
              models=()) -> dict:
    """The case of ``seed`` for ``model`` (``variables`` from :func:`variable_table`).

    ``kind`` (default: drawn from :data:`KINDS`, without :data:`WRAPPER_KINDS` unless
    ``wrapper``) says what is made hostile; the rest stays mostly sane so that the case
    reaches the calls it is about.  A case is JSON: ``model``, ``kind``, ``seed``,
    ``instance_name``, ``logging``, ``start_time``, ``parameters`` ([name, value]) set in
    initialisation mode, and ``ops``: ["set", name, value], ["step", t, h] (t None: the
    last point plus the last step), ["get"], ["terminate"], ["get_state"], ["set_state"],
    ["set_vr", type, vr, value] (a raw value reference), ["state_bytes", variant, seed,
    other model] (bytes of :data:`STATE_VARIANTS` deserialised, and set if taken), and the
    out-of-order calls of :data:`LIFECYCLE_CALLS`; ``guid`` "wrong" instantiates with
    another GUID.
    ``models`` (all FMUs of the run) gives "foreign" states their source.

    A drawn value is hostile (:data:`HOSTILE_REALS` ...) with probability 0.6 in a "parameters"
    case, 0.3 for a "strings" case's parameters, 0.2 for an "inputs" case's inputs (set before
    every step; the other kinds set them once, sane, within 2 % of :data:`SANE_INPUTS` or the
    start), 0.5 for a "sets" case's outputs and 0.3 for its parameters; a sane Real is within
    50 % of its start.
    """
    rng = random.Random(f"{model}:{seed}")
    kinds = [k for k in KINDS if wrapper or k not in WRAPPER_KINDS]
    kind = kind or rng.choice(kinds)
    by_causality = {}
    for name, type_, causality, variability, start in variables:
        if name == "error":
            continue
        by_causality.setdefault(causality, []).append((name, type_, start))
    parameters_ = by_causality.get("parameter", [])
    inputs = by_causality.get("input", [])
    outputs = by_causality.get("output", [])

    hostile_parameters = {"parameters": 0.6, "strings": 0.3}.get(kind, 0.0)
    chosen = rng.sample(parameters_, min(len(parameters_), rng.randint(1, 3))) if parameters_ else []
    parameters = []
    for name, type_, start in chosen:
        if kind == "strings" and type_ != "String":
            continue
        if kind in ("parameters", "strings"):
            parameters.append([name, _value(rng, type_, start, hostile_parameters)])
    if kind == "strings":
        strings = [p for p in parameters_ if p[1] == "String"]
        if strings:
            name, _, _ = rng.choice(strings)
            parameters.append([name, rng.choice(HOSTILE_STRINGS)])

    instance_name = "instance"
    if kind == "strings":
        instance_name = rng.choice(("instance", "%s%s%s%s%n", "é#%41", "a" * 300, ""))

    ops = []
    t = 0.0
    n_steps = rng.randint(1, 5)
    for k in range(n_steps):
        sane = SANE_INPUTS.get(model, {})
        for name, type_, start in inputs:
            hostile = 0.2 if kind == "inputs" else 0.0
            if type_ == "Real" and (kind == "inputs" or k == 0):
                ops.append(["set", name, _value(rng, type_, sane.get(name, start), hostile, spread=0.02)])
        h = rng.choice(STEP_SIZES) if kind == "steps" else 1e-3
        point = None
        if kind == "order" and rng.random() < 0.4:
            point = rng.choice((0.0, -1.0, t + 0.5, t - 1e-3, math.nan, 1e300))
        ops.append(["step", point, h])
        if kind == "order" and rng.random() < 0.3:
            ops.append(rng.choice((["terminate"], ["get_state"], ["set_state"], ["get"])))
        ops.append(["get"])
        t += h if math.isfinite(h) else 0.0
    if kind == "order" and rng.random() < 0.5:
        ops.insert(0, ["step", 0.0, 1e-3])            # before initialisation: runs in the init phase
        ops[0] = ["step_before_init", 0.0, 1e-3]
    if kind == "state":
        others = [m for m in models if m != model] or [model]
        ops.insert(rng.randint(1, len(ops)), ["state_bytes", rng.choice(STATE_VARIANTS), rng.randrange(2 ** 31),
                                              rng.choice(others)])
    start_time = rng.choice(START_TIMES) if kind == "start" else 0.0
    guid = "wrong" if kind == "lifecycle" and rng.random() < 0.2 else "own"
    if kind == "lifecycle" and guid == "own":
        for _ in range(rng.randint(1, 3)):
            ops.insert(rng.randint(0, len(ops)), [rng.choice(LIFECYCLE_CALLS[:-1])])
    if kind == "sets":
        for _ in range(rng.randint(1, 3)):
            choice = rng.random()
            if choice < 0.35 and outputs:
                name, type_, start = rng.choice(outputs)
                ops.insert(rng.randint(0, len(ops)), ["set", name, _value(rng, type_, start, 0.5)])
            elif choice < 0.7 and parameters_:
                name, type_, start = rng.choice(parameters_)
                ops.insert(rng.randint(0, len(ops)), ["set", name, _value(rng, type_, start, 0.3)])
            else:
                type_ = rng.choice(("Real", "Integer", "Boolean", "String"))
                ops.insert(rng.randint(0, len(ops)), ["set_vr", type_, rng.choice((999999, 2 ** 32 - 1, 0, 1)),
                                                      _value(rng, type_, None, 0.5)])
    return {"model": model, "kind": kind, "seed": seed, "instance_name": instance_name,
            "logging": rng.random() < 0.7, "start_time": start_time, "guid": guid, "parameters": parameters,
            "ops": ops}


# --- running cases in workers --------------------------------------------------------------------

@dataclass
class CaseResult:
    """What happened to one case (:data:`OUTCOMES`), the statuses and the problems found."""

    case: dict
    outcome: str
    statuses: list = field(default_factory=list)
    problems: list = field(default_factory=list)
    seconds: float = 0.0


def run_cases(cases: list, unzipped: dict, batch: int = 30, case_timeout: float = CASE_TIMEOUT,
              progress=None, env: dict | None = None) -> list:
    """Run ``cases`` in worker subprocesses, ``batch`` cases a worker; a crashed, hung or
    fatal case ends its worker and the next cases go to a new one.

    ``unzipped`` maps a model to its FMU extracted once (all workers import the same
    sources); ``env`` adds to the workers' environment (:func:`sanitizer_env` for FMUs
    built with AddressSanitizer).
    """
    results = [None] * len(cases)
    pending = list(range(len(cases)))
    while pending:
        chunk = pending[:batch]
        done = _run_worker([cases[i] for i in chunk], unzipped, case_timeout, env)
        for offset, result in enumerate(done):
            results[chunk[offset]] = result
            if progress is not None:
                progress(result)
        pending = pending[len(done):] if done else pending[1:]
    return results


def _run_worker(cases: list, unzipped: dict, case_timeout: float, extra_env: dict | None = None) -> list:
    """Run ``cases`` in one worker; the results of those it finished, the last one a crash,
    hang or fatal if the worker ended there."""
    read_fd, write_fd = os.pipe()
    env = {**os.environ, **(extra_env or {}), "HOSTILE_RESULT_FD": str(write_fd),
           "PYTHONPATH": os.pathsep.join(filter(None, [str(Path(__file__).resolve().parents[2]),
                                                        os.environ.get("PYTHONPATH")]))}
    payload = json.dumps({"unzipped": {k: str(v) for k, v in unzipped.items()}, "cases": cases})
    process = subprocess.Popen([sys.executable, "-m", "fmus.hostile.worker"], stdin=subprocess.PIPE,
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env,
                               pass_fds=(write_fd,))
    os.close(write_fd)
    results = []
    buffer = b""
    try:
        process.stdin.write(payload.encode())
        process.stdin.close()
        deadline = time.monotonic() + case_timeout
        started = time.monotonic()
        while len(results) < len(cases):
            ready, _, _ = select.select([read_fd], [], [], max(0.0, deadline - time.monotonic()))
            if not ready:
                process.kill()
                results.append(CaseResult(cases[len(results)], "hang", problems=[
                    f"no result within {case_timeout:g} s"], seconds=time.monotonic() - started))
                break
            chunk = os.read(read_fd, 1 << 16)
            if not chunk:      # the worker ended before the case's result
                code = process.wait()
                outcome = "crash" if code != EXIT_AFTER_FATAL else "fatal"
                results.append(CaseResult(cases[len(results)], outcome, problems=[
                    f"worker exit status {code}" + (f" (signal {-code})" if code < 0 else "")],
                    seconds=time.monotonic() - started))
                break
            buffer += chunk
            while b"\n" in buffer:
                line, buffer = buffer.split(b"\n", 1)
                data = json.loads(line)
                results.append(CaseResult(cases[len(results)], data["outcome"], data["statuses"],
                                          data["problems"], data["seconds"]))
                deadline = time.monotonic() + case_timeout
                started = time.monotonic()
                if data["outcome"] == "fatal":
                    break
            if results and results[-1].outcome == "fatal":
                break
    finally:
        os.close(read_fd)
        if process.poll() is None:
            process.kill()
        process.wait()
    return results


def summary(results: list) -> dict:
    """{(model, kind): {outcome: count}} and the totals per model under kind "all"."""
    table = {}
    for r in results:
        for key in ((r.case["model"], r.case["kind"]), (r.case["model"], "all")):
            counts = table.setdefault(key, dict.fromkeys(OUTCOMES, 0))
            counts[r.outcome] += 1
    return table


def markdown_summary(results: list) -> str:
    """The summary as a markdown table: one row per FMU and kind, outcome counts."""
    table = summary(results)
    lines = ["| FMU | kind | cases | " + " | ".join(OUTCOMES) + " |", "|---|---|---|" + "---|" * len(OUTCOMES)]
    for (model, kind), counts in sorted(table.items(), key=lambda kv: (kv[0][0], kv[0][1] != "all", kv[0][1])):
        total = sum(counts.values())
        label = f"**{kind}**" if kind == "all" else kind
        lines.append(f"| {model} | {label} | {total} | " + " | ".join(str(counts[o]) for o in OUTCOMES) + " |")
    return "\n".join(lines)


def extract_fmus(paths: dict, directory) -> dict:
    """Extract each FMU (model -> .fmu path) once under ``directory``: model -> its directory."""
    from fmpy import extract

    directory = Path(directory)
    unzipped = {}
    for model, path in paths.items():
        target = directory / model
        if not (target / "modelDescription.xml").exists():
            target.mkdir(parents=True, exist_ok=True)
            extract(str(path), unzipdir=str(target))
        unzipped[model] = target
    return unzipped


def prepared_fmus(fmu_dir, models, work) -> dict:
    """The FMUs to drive, extracted under ``work``: those of ``fmu_dir`` (every ``*.fmu``)
    or, without it, all of ``parcosim build`` built under ``work``; ``models`` (a
    comma-separated string, or None for all) picks some.  Model -> its directory."""
    if fmu_dir:
        paths = {p.stem: p for p in Path(fmu_dir).glob("*.fmu")}
    else:
        from fmus.export.build import build_all
        paths = {p.stem: p for p in build_all(Path(work) / "build")}
    if models:
        unknown = [m for m in models.split(",") if m not in paths]
        if unknown:
            raise ValueError(f"no FMU {unknown}; available: {', '.join(sorted(paths))}")
        paths = {m: paths[m] for m in models.split(",")}
    return extract_fmus(paths, Path(work) / "fmus")


def wrapper_is_ours(unzip_dir, model: str) -> bool:
    """Whether the extracted FMU's binary is parcosim's own FMI wrapper (checked in a
    subprocess: loading the binary here would start its Python in this process).  The binary
    is named by the FMU's modelIdentifier, which need not be ``model`` (the FMU's file name:
    ``SpecPlant_delta3.fmu`` holds ``SpecPlant.so``)."""
    from fmpy import read_model_description

    identifier = read_model_description(str(unzip_dir)).coSimulation.modelIdentifier
    code = ("import sys; from fmus.slave.base import wrapper_symbol_present; "
            "sys.exit(0 if wrapper_symbol_present(sys.argv[1], sys.argv[2]) else 1)")
    root = str(Path(__file__).resolve().parents[2])
    run = subprocess.run([sys.executable, "-c", code, str(Path(unzip_dir) / "resources"), identifier],
                         env={**os.environ, "PYTHONPATH": root}, capture_output=True, timeout=120)
    return run.returncode == 0


def cases_for(model: str, unzip_dir, seeds, wrapper: bool = False, kinds=None) -> list:
    """One case per seed; with ``kinds`` the kinds cycle over the seeds (every kind covered)."""
    from fmpy import read_model_description

    variables = variable_table(read_model_description(str(unzip_dir)))
    models = sorted(p.name for p in Path(unzip_dir).parent.iterdir() if (p / "modelDescription.xml").exists())
    return [make_case(model, variables, seed, kind=kinds[i % len(kinds)] if kinds else None, wrapper=wrapper,
                      models=models)
            for i, seed in enumerate(seeds)]


# --- native FMUs (issue 28) ----------------------------------------------------------------------

#: Exit statuses of a worker stopped by AddressSanitizer / UndefinedBehaviorSanitizer (a crash).
ASAN_EXIT, UBSAN_EXIT = 99, 98


def sanitizer_env(log_dir=None) -> dict:
    """The environment of a worker that loads FMUs built with ``-fsanitize=address,undefined``:
    the ASan runtime preloaded (Python is not built with it; libstdc++ after it, as in
    tests/kernels/test_sanitizers.py), Python's allocations through malloc and not checked for leaks,
    and any report ending the worker (a crash of the case), written under ``log_dir`` if
    given (files ``asan.PID``, ``ubsan.PID``)."""
    from kernels import build

    def runtime(name):
        path = subprocess.run([build.compiler(), f"-print-file-name={name}"], capture_output=True, text=True,
                              check=True).stdout.strip()
        return path if os.path.isabs(path) and os.path.exists(path) else None

    asan = runtime("libasan.so")
    if asan is None:
        raise RuntimeError("the C compiler has no AddressSanitizer runtime (libasan.so)")
    asan_log = ubsan_log = ""
    if log_dir is not None:
        Path(log_dir).mkdir(parents=True, exist_ok=True)
        asan_log, ubsan_log = (f":log_path={Path(log_dir).resolve() / name}" for name in ("asan", "ubsan"))
    return {"LD_PRELOAD": " ".join(filter(None, (asan, runtime("libstdc++.so.6")))), "PYTHONMALLOC": "malloc",
            "ASAN_OPTIONS": f"detect_leaks=0:exitcode={ASAN_EXIT}{asan_log}",
            "UBSAN_OPTIONS": f"halt_on_error=1:print_stacktrace=1:exitcode={UBSAN_EXIT}{ubsan_log}"}


def is_native(unzip_dir) -> bool:
    """Whether the extracted FMU is one of parcosim's native FMUs (its build identity says
    ``"native": true``): a C binary that answers every kind of case with FMI 2.0's statuses,
    as parcosim's wrapper does (:data:`WRAPPER_KINDS` included)."""
    from fmus.slave.identity import IDENTITY_FILE

    identity = Path(unzip_dir) / "resources" / IDENTITY_FILE
    try:
        return bool(json.loads(identity.read_text(encoding="utf-8")).get("native"))
    except (OSError, ValueError):
        return False


def sanitized_from_sources(fmu, out_dir) -> Path:
    """A copy of the native FMU ``fmu`` in ``out_dir`` whose binary is compiled again from the
    FMU's own ``sources/*.c`` (and the FMI 2.0 headers fmpy ships) with
    ``-fsanitize=address,undefined`` (:data:`kernels.build.SANITIZE`): what the campaign
    drives under :func:`sanitizer_env`.  Raises RuntimeError if the sources do not compile."""
    import shutil
    import tempfile
    import zipfile

    import fmpy
    from fmpy import read_model_description

    from kernels import build

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="hostile-asan-") as tmp:
        unzip = Path(tmp) / "fmu"
        with zipfile.ZipFile(fmu) as z:
            z.extractall(unzip)
        identifier = read_model_description(str(unzip)).coSimulation.modelIdentifier
        sources = sorted((unzip / "sources").glob("*.c"))
        if not sources:
            raise RuntimeError(f"{fmu} carries no sources/*.c to compile")
        binary = unzip / "binaries" / fmpy.platform / f"{identifier}.so"
        command = [build.compiler(), "-std=c11", "-fPIC", "-shared", "-ffp-contract=off", *build.SANITIZE,
                   f"-I{unzip / 'sources'}", f"-I{Path(fmpy.__file__).resolve().parent / 'c-code'}",
                   *map(str, sources), "-o", str(binary), "-lm"]
        done = subprocess.run(command, capture_output=True, text=True)
        if done.returncode != 0:
            raise RuntimeError(f"{fmu}: its sources do not compile with the sanitizers:\n{done.stderr[-2000:]}")
        target = out_dir / Path(fmu).name
        archive = shutil.make_archive(str(Path(tmp) / "copy"), "zip", unzip)
        shutil.move(archive, target)
    return target


def prepared_native_fmus(fmu_dir, models, work, sanitize: bool = True, loop_fmu=None) -> dict:
    """The native FMUs to drive, extracted under ``work``: those of ``fmu_dir`` (every
    ``*.fmu``) or, without it, all of ``parcosim build --native`` built under ``work``, and
    with ``loop_fmu`` that native ClosedLoop (written by ``parcosim export-fmu SCENE
    LOOP.fmu --native``; the campaign sits below the scenes, so it takes the file); with ``sanitize`` each rebuilt from its own sources by
    :func:`sanitized_from_sources`.  Model -> its directory."""
    if fmu_dir:
        paths = {p.stem: p for p in Path(fmu_dir).glob("*.fmu")}
    else:
        from fmus.native.build import build_native_all
        paths = {p.stem: p for p in build_native_all(Path(work) / "native")}
    if loop_fmu:
        paths["ClosedLoop"] = Path(loop_fmu)
    if models:
        unknown = [m for m in models.split(",") if m not in paths]
        if unknown:
            raise ValueError(f"no FMU {unknown}; available: {', '.join(sorted(paths))}")
        paths = {m: paths[m] for m in models.split(",")}
    if sanitize:
        paths = {m: sanitized_from_sources(p, Path(work) / "sanitized") for m, p in paths.items()}
    return extract_fmus(paths, Path(work) / "fmus")
