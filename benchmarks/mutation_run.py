"""Running a :mod:`benchmarks.mutation_py` campaign: each mutant in a copy of the draw's tree,
against the tests, anywhere in the suite, that execute its lines (:mod:`benchmarks.mutation_map`;
a C mutant's: :mod:`benchmarks.mutation_cmap`).

    python -m benchmarks.mutation_py --seed 3101 --sample 300 --workers 2     # run (resumes)
    python -m benchmarks.mutation_py --seed 3601 --rerun-survivors FROM.jsonl --results NEW.jsonl

A run is ``pytest -x`` of the selected tests with a CPU-time limit (the wall clock's is
:data:`WALL_FACTOR` times longer: on shared cores a run mostly waits for one).  A re-run
(:func:`rerun`) takes an earlier campaign's file of the same draw, keeps its killed and not
viable mutants as they are (a wider selection only adds tests) and runs the others again
with this module's selection, into a new file (``--language c``: its C mutants only).

A run that fails loudly rather than by a failing test (:data:`LOUD`: the selected test files no
longer collect, pytest's exit status 4; a crash, a signal; pytest's internal error, status 3)
fails a CI run all the same: it counts as killed, with ``killed_by`` naming the kind, when the
same selection passes on the unmutated tree (run once more for it; a collection failure: collected
once more); otherwise its outcome is
``baseline failure``, counted neither way (as :func:`confirm`'s).  A run that fails by a test
has ``killed_by`` "test".
"""
from __future__ import annotations

import json
import os
import re
import resource
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict
from pathlib import Path

from benchmarks import mutation_c, mutation_map, mutation_py

ROOT = mutation_py.ROOT
#: The test files a C mutant's selection draws from (``--c-test-files``): every test file by
#: default; a narrower set of patterns maps fewer files (a measurement of limited time).
C_TESTS: tuple = ()
#: pytest's exit statuses that fail loudly, by what ``killed_by`` calls them (a signal: "crash").
LOUD = {3: "internal error", 4: "collection"}
#: A test run's wall-clock limit, in multiples of its CPU-time limit (``--timeout``).
WALL_FACTOR = 8
#: The outcomes a re-run decides again (killed and not viable stay as they were; ``error``, a loud
#: failure of a campaign before :data:`LOUD` counted, is decided again).
RERUN = ("survived", "timeout", "error")
#: How a selection is named in the results (:func:`select`).
KINDS = {"coverage": "coverage", "import": "import (a line run at import: the module's tests, then its importers')",
         "none": "none", "enclosing": "enclosing (a C line gcov counts for no test: the tests of its function)"}


def results_path(seed: int) -> Path:
    """Where a seed's campaign keeps its outcomes: one JSON line a mutant, appended as each is
    decided (a restart resumes), in the repository."""
    return ROOT / "benchmarks" / "results" / f"mutation_{seed}.jsonl"


def make_copy(where: Path, commit: str = "HEAD") -> Path:
    """The committed tree (``git archive <commit>``) at ``where``, with the built kernels library."""
    shutil.rmtree(where, ignore_errors=True)
    where.mkdir(parents=True)
    archive = subprocess.run(["git", "archive", commit], cwd=ROOT, check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(where)], input=archive, check=True)
    shutil.copy2(mutation_c.kbuild.build(), where / "kernels" / mutation_c.kbuild.LIBRARY.name)
    return where


def _cpu_limit(seconds: float):
    """The child's CPU-time limit (SIGXCPU past it): on shared cores a wall-clock limit ends
    runs that were only waiting for a core."""
    def limit():
        resource.setrlimit(resource.RLIMIT_CPU, (int(seconds), int(seconds) + 5))
    return limit


def _pytest(copy: Path, tests: list, timeout: float, env: dict, collect_only: bool = False) -> dict:
    """``pytest -x`` of ``tests`` (files or node ids, in that order) in ``copy``, at most
    ``timeout`` CPU seconds (and :data:`WALL_FACTOR` times as many on the wall clock);
    ``collect_only``: their collection only."""
    cache = tempfile.mkdtemp(prefix="parcosim_mutcache_")
    env = dict(env, PYTHONDONTWRITEBYTECODE="1", PARCOSIM_CACHE=cache,
               PYTHONPATH=os.pathsep.join([str(copy), *mutation_map._other_paths()]))
    listed = Path(cache) / "tests.txt"
    listed.write_text("\n".join(tests) + "\n")
    start = time.monotonic()
    try:
        command = mutation_map.pytest_command(copy, "-x", "-rf", *(["--collect-only"] if collect_only else []),
                                              f"@{listed}")
        done = subprocess.run(command, cwd=copy, env=env, timeout=WALL_FACTOR * timeout,
                              capture_output=True, text=True, preexec_fn=_cpu_limit(timeout))
    except subprocess.TimeoutExpired:
        return {"outcome": "timeout", "seconds": WALL_FACTOR * timeout, "cpu_limit": timeout}
    finally:
        shutil.rmtree(cache, ignore_errors=True)
    seconds = round(time.monotonic() - start, 1)
    if done.returncode == -signal.SIGXCPU:
        return {"outcome": "timeout", "seconds": seconds, "cpu_limit": timeout}
    failed = re.findall(r"^(?:FAILED|ERROR) (\S+)", done.stdout, re.M)
    outcome = {0: "survived", 1: "killed", 2: "killed", 5: "survived"}.get(done.returncode, "error")
    kind = loud(done.returncode)
    return {"outcome": "loud" if kind else outcome, "seconds": seconds, "returncode": done.returncode,
            "failed": failed[:1], "cpu_limit": timeout, **({"killed_by": kind or "test"} if kind or
                                                          outcome == "killed" else {})}


def loud(returncode: int) -> str | None:
    """What a run's exit status that fails loudly (not by a test) is called, or None."""
    if returncode < 0:
        return "crash"
    return LOUD.get(returncode)


def decide_loud(result: dict, pristine) -> dict:
    """``result`` of :func:`_pytest`, a loud one decided: killed when ``pristine(collect_only)``
    (the same selection on the unmutated tree, a :func:`_pytest` answer; for a collection
    failure its collection only, seconds where the run may take minutes) passes, else
    ``baseline failure`` with that run's exit status."""
    if result["outcome"] != "loud":
        return result
    baseline = pristine(result["killed_by"] == "collection")
    if baseline["outcome"] == "survived":
        return dict(result, outcome="killed")
    return dict(result, outcome="baseline failure", baseline_returncode=baseline.get("returncode"))


def _limit(cost: float, base: float, factor: float) -> float:
    """A run's CPU-time limit from its tests' measured seconds."""
    return round(base + factor * cost)


def run_python(copy: Path, mutant: mutation_py.PyMutant, chosen: dict, base: float, factor: float) -> dict:
    """Run ``mutant`` against ``chosen`` (:func:`select`'s answer)."""
    path = copy / mutant.file
    original = path.read_text()
    mutated = mutant.apply(original)
    try:
        compile(mutated, str(path), "exec")
    except SyntaxError:
        return {"outcome": "not viable", "seconds": 0.0}
    if not chosen["tests"]:
        return {"outcome": "survived", "seconds": 0.0, "note": chosen["note"]}
    limit = _limit(chosen["cost"], base, factor)
    try:
        path.write_text(mutated)
        result = _pytest(copy, chosen["tests"], limit, dict(os.environ))
    finally:
        path.write_text(original)
    return decide_loud(result, lambda collect: _pytest(copy, chosen["tests"], limit, dict(os.environ), collect))



def run_c(copy: Path, mutant, chosen: dict, base: float, factor: float) -> dict:
    work = Path(tempfile.mkdtemp(prefix="parcosim_cmut_"))
    try:
        sources = work / "src"
        shutil.copytree(copy / "kernels" / "src", sources)
        target = sources / mutant.file
        target.write_text(mutant.apply(target.read_text()))
        try:
            library = mutation_c.build_from(sources, work / "libparcosim_kernels.so")
        except subprocess.CalledProcessError:
            return {"outcome": "not viable", "seconds": 0.0}
        if not chosen["tests"]:
            return {"outcome": "survived", "seconds": 0.0, "note": chosen["note"]}
        limit = _limit(chosen["cost"], base, factor)
        result = _pytest(copy, chosen["tests"], limit, dict(os.environ, PARCOSIM_KERNELS_LIB=str(library)))
    finally:
        shutil.rmtree(work, ignore_errors=True)
    pristine = {k: v for k, v in os.environ.items() if k != "PARCOSIM_KERNELS_LIB"}     # the copy's own library
    return decide_loud(result, lambda collect: _pytest(copy, chosen["tests"], limit, pristine, collect))


_MAPS: dict = {}


def _linemap(copy: Path, files: list, lock_of, commit: str, language: str = "python") -> dict:
    """The merged map of ``files`` at ``commit`` (built where missing), kept for the next mutant."""
    if (commit, tuple(files), language) not in _MAPS:
        _MAPS[(commit, tuple(files), language)] = mutation_map.for_files(
            copy, mutation_py.python_files(), files, lock_of, commit, language=language)
    return _MAPS[(commit, tuple(files), language)]


class NeedsSlowMaps(Exception):
    """No test outside the slow files would run for this mutant: its selection needs their maps."""


def select(copy: Path, name: str, mutant, importers: list, budget: float, lock_of=None, commit: str = "HEAD",
           slow_maps: bool = True) -> dict:
    """The tests a mutant runs.  Python: those tests, of every test file of ``copy``, that
    execute a line it changes (in process or in a process they start), the cheaper first
    within ``budget`` measured seconds; for a line run at import, the tests that execute its
    module, then those of ``importers`` (the test files that import the module);
    none when nothing executes it (:func:`benchmarks.mutation_map.select`; every file's map
    built in ``copy`` the first time).  The :data:`benchmarks.mutation_map.SLOW` files are
    mapped only for a mutant that no test marked slow would run from the others (their tests
    are all slow, and a slow test runs only when no other does: the selection is the same);
    ``slow_maps=False``: raise :class:`NeedsSlowMaps` instead.  C: the same, from the C maps
    (:mod:`benchmarks.mutation_cmap`) of the test files :data:`C_TESTS` matches (every one
    by default); a C line has no import time."""
    every = mutation_map.all_test_files(copy)
    language = "c" if name.endswith(".c") else "python"
    if language == "c":
        if C_TESTS:
            every = [f for f in every if any(Path(f).match(pattern) for pattern in C_TESTS)]
        at_import = False
        enclosing = mutation_map.c_function_lines((copy / name).read_text(), mutant.line)
    else:
        body = mutation_map.function_lines((copy / name).read_text())
        at_import = any(line not in body for line in range(mutant.line, mutant.end_line + 1))
        enclosing = range(0)
    quick = [f for f in every if not mutation_map.SLOW.search((copy / f).read_text())]
    for files in (quick, every):
        linemap = _linemap(copy, files, lock_of, commit, language)
        chosen = mutation_map.select(linemap, name, mutant.line, getattr(mutant, "end_line", mutant.line), budget,
                                     at_import, tuple(importers), enclosing)
        slow = dict(zip(linemap["tests"], linemap["slow"]))
        if any(not slow[t] for t in chosen["tests"]):
            break
        if not slow_maps:
            raise NeedsSlowMaps(name)
    kind = chosen.pop("kind")
    if kind == "none":
        note = {"note": "no test executes the line"}
    elif not chosen["tests"]:      # covered only by tests marked slow, each over the budget
        note = {"note": f"only tests marked slow execute the line, each over the {budget:g} s budget"}
    else:
        note = {}
    return dict(chosen, selection=KINDS[kind], **note)


def _record(name, mutant) -> dict:
    return {**asdict(mutant), "file": name, "language": "c" if name.endswith(".c") else "python"}


def read_results(results: Path) -> tuple:
    """(header, {index: outcome record}) of a campaign's JSON-lines file (the last line of an
    index wins: ``--retry-timeouts`` appends)."""
    header, done = None, {}
    for line in results.read_text().splitlines():
        if line.strip():
            entry = json.loads(line)
            if "header" in entry:
                header = entry["header"]
            else:
                done[entry["index"]] = entry
    return header, done


def _draw_of(header: dict, results: Path) -> list:
    """The draw of ``header``'s seed and sample from this tree, refused if it is not the recorded one."""
    chosen = mutation_py.draw(mutation_py.pool_by_file(), header["seed"], header["sample"])
    if header.get("drawn") and header["drawn"] != [name for name, _ in chosen]:
        raise ValueError(f"{results} was drawn from the product files of commit {header['commit'][:10]}; "
                         f"this tree's draw differs (a file moved or changed since): resume from a checkout "
                         f"of that commit (git worktree add --detach DIR {header['commit'][:10]}) with this "
                         f"tool's benchmarks/mutation_*.py copied into it")
    return chosen


def _run_all(chosen: list, pending: list, header: dict, results: Path, done: dict, workers: int,
             base: float, factor: float, budget: float) -> None:
    """Run the mutants ``pending`` (indices into ``chosen``), ``workers`` at once, each in a
    copy of ``header["commit"]``; each outcome is appended to ``results`` as it comes.  Those
    whose selection needs the slow files' maps (:class:`NeedsSlowMaps`) run last."""
    copies = [make_copy(Path(tempfile.gettempdir()) / f"parcosim_mutpy_{os.getpid()}_{w}", header["commit"])
              for w in range(workers)]
    importers = mutation_py.importers(copies[0])   # the tests of the draw's commit: tests written since are not run
    lock, shards = threading.Lock(), {}

    def lock_of(test_file):            # one worker builds a test file's map, the other waits for it
        with lock:
            return shards.setdefault(test_file, threading.Lock())

    free = list(copies)

    deferred = []

    def one(k, slow_maps=False):
        name, mutant = chosen[k]
        with lock:
            copy = free.pop()
        try:
            tests = select(copy, name, mutant, importers.get(mutation_py.module_name(name), []), budget, lock_of,
                           header["commit"], slow_maps)
            run = run_c if name.endswith(".c") else run_python
            result = run(copy, mutant, tests, base, factor)
        except NeedsSlowMaps:
            deferred.append(k)       # after the others: the slow files are mapped once, for all of these
            return
        finally:
            with lock:
                free.append(copy)
        entry = {"index": k, **_record(name, mutant), **result, "selection": tests["selection"],
                 "covering": tests["covering"], "selected": len(tests["tests"] or []), "cost": tests["cost"]}
        with lock:
            with results.open("a") as out:
                out.write(json.dumps(entry) + "\n")
            done[k] = entry
            print(f"[{len(done)}/{len(chosen)}] {name}:{mutant.line} {mutant.operator} {mutant.before[:50]!r} -> "
                  f"{mutant.after[:50]!r}: {result['outcome']} ({result['seconds']} s, {entry['selected']} tests)",
                  flush=True)

    try:
        with ThreadPoolExecutor(workers) as pool_:
            list(pool_.map(one, pending))
            list(pool_.map(lambda k: one(k, slow_maps=True), sorted(deferred)))
    finally:
        for copy in copies:
            shutil.rmtree(copy, ignore_errors=True)


def campaign(seed: int, sample: int, workers: int, results: Path | None = None, retry_timeouts: bool = False,
             base: float = 30.0, factor: float = 3.0, budget: float = 300.0) -> Path:
    """Draw ``sample`` mutants with ``seed`` and run them, each against the tests that execute
    its lines (``budget``: at most so many measured seconds of them), with ``pytest -x`` and a
    CPU-time limit of ``base + factor * (their measured seconds)``; each outcome is appended
    to ``results`` as it comes (a restart with the same seed and sample resumes)."""
    results = results or results_path(seed)
    done = {}
    if results.exists():
        header, done = read_results(results)
        if header["seed"] != seed or header["sample"] != sample:
            raise ValueError(f"{results} holds seed {header['seed']}, sample {header['sample']}, "
                             f"not seed {seed}, sample {sample}")
        chosen = _draw_of(header, results)
    else:
        pool = mutation_py.pool_by_file()
        chosen = mutation_py.draw(pool, seed, sample)
        commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True).stdout.strip()
        results.parent.mkdir(parents=True, exist_ok=True)
        header = {"seed": seed, "sample": len(chosen), "commit": commit, "map": mutation_map.key(),
                  "selection": "global", "base_seconds": base, "factor": factor, "budget_seconds": budget,
                  "pool": {name: len(ms) for name, ms in pool.items()},
                  "lines": {name: mutation_py.line_count(name) for name in pool},
                  "drawn": [name for name, _ in chosen]}
        results.write_text(json.dumps({"header": header}) + "\n")
    pending = [k for k in range(len(chosen)) if k not in done]
    if retry_timeouts:     # after the rest
        pending += [k for k, m in sorted(done.items()) if m["outcome"] == "timeout"]
    _run_all(chosen, pending, header, results, done, workers, base, factor, budget)
    return results


def rerun(source: Path, results: Path, workers: int = 1, base: float = 30.0, factor: float = 3.0,
          budget: float = 300.0, language: str | None = None, outcomes: tuple = RERUN) -> Path:
    """Run again, with this module's selection, the mutants of ``source`` (an earlier
    campaign's file) whose outcome is one of ``outcomes`` (default :data:`RERUN`; of
    ``language``, "c" or "python", only when given), into ``results`` (a new file, resumed when
    it exists); the others are copied as they were (``"carried": true``).  Refused when this
    tree draws other mutants than ``source`` recorded, or when ``results`` is the re-run of
    another file."""
    if results.resolve() == source.resolve():
        raise ValueError(f"--results {results} is the file re-run: write the re-run to a new file")
    old_header, before = read_results(source)
    chosen = _draw_of(old_header, source)
    for k, entry in before.items():
        name, mutant = chosen[k]
        if (entry["file"], entry["line"], entry["operator"], entry["after"]) != (name, mutant.line, mutant.operator,
                                                                                 getattr(mutant, "after", None)):
            raise ValueError(f"{source}: mutant {k} is {entry['file']}:{entry['line']} {entry['operator']}, "
                             f"this tree draws {name}:{mutant.line} {mutant.operator}")
    if results.exists():
        header, done = read_results(results)
        if header.get("rerun_of") != str(source) or header["seed"] != old_header["seed"]:
            raise ValueError(f"{results} is not a re-run of {source} (it holds {header.get('rerun_of')!r}, "
                             f"seed {header['seed']})")
    else:
        header = {**{k: v for k, v in old_header.items() if k != "near_files"}, "rerun_of": str(source),
                  "selection": "global", "map": mutation_map.key(commit=old_header["commit"]),
                  "base_seconds": base, "factor": factor, "budget_seconds": budget, "language": language,
                  "outcomes": list(outcomes),
                  "c_test_files": list(C_TESTS)}
        done = {k: dict(m, carried=True) for k, m in before.items() if not _rerun(m, language, outcomes)}
        results.parent.mkdir(parents=True, exist_ok=True)
        results.write_text("\n".join(json.dumps(line) for line in [{"header": header}, *done.values()]) + "\n")
    pending = [k for k in sorted(before) if _rerun(before[k], language, outcomes) and k not in done]
    _run_all(chosen, pending, header, results, done, workers, base, factor, budget)
    return results


def _rerun(entry: dict, language: str | None, outcomes: tuple) -> bool:
    """Whether a re-run of ``outcomes`` (of ``language``'s mutants only, when given) runs ``entry`` again."""
    return entry["outcome"] in outcomes and language in (None, entry.get("language"))


def confirm(results: Path, timeout: float) -> dict:
    """Run every killing test once more, all in one run, on the unmutated tree; a kill by a
    test that fails there too is appended again as ``baseline failure``."""
    header, done = read_results(results)
    killers = sorted({t for m in done.values() if m["outcome"] == "killed" for t in m.get("failed", [])})
    copy = make_copy(Path(tempfile.gettempdir()) / f"parcosim_mutpy_confirm_{os.getpid()}")
    try:
        ran = _pytest_all(copy, killers, timeout * max(1, len(killers)))
    finally:
        shutil.rmtree(copy, ignore_errors=True)
    failing = set(re.findall(r"^(?:FAILED|ERROR) (\S+)", ran.stdout, re.M))
    with results.open("a") as out:
        for m in done.values():
            if m["outcome"] == "killed" and m.get("failed") and m["failed"][0] in failing:
                out.write(json.dumps(dict(m, outcome="baseline failure")) + "\n")
    return {"tests": len(killers), "returncode": ran.returncode, "failing_on_the_unmutated_tree": sorted(failing)}


def _pytest_all(copy: Path, tests: list, timeout: float):
    env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1",
               PYTHONPATH=os.pathsep.join([str(copy), *mutation_map._other_paths()]))
    return subprocess.run(mutation_map.pytest_command(copy, "-rf", *tests),
                          cwd=copy, env=env, timeout=WALL_FACTOR * timeout, capture_output=True, text=True)

