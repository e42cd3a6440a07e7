"""Which tests execute which product line: the map that makes a mutant cheap (issue 31).

Each test file runs once per state of the product and the tests, the first time a mutant
asks for it, under coverage with pytest-cov's per-test contexts (``--cov-context=test``) and
:mod:`benchmarks.mutation_timing` (what each test costs, which fail anyway, which are marked
slow), in a copy of the committed tree.  Files are measured wherever they run from under the
temporary directory (the copy, and the FMUs' bundles unzipped by an importer: a bundled
``.../plant/drive.py`` counts as ``plant/drive.py``).  A test's subprocesses are measured too
(``coverage.process_startup``) and count as that test's: the timing plugin puts the running
test's node id in ``$PARCOSIM_TEST_CONTEXT`` and the configuration takes it as a process's
static context.  The map of a test file is a gzipped JSON file named by a key of the
product's files, that test file's, the tests' helpers and :data:`FORMAT` (:func:`key`), so a
commit that changes none of them keeps it.  Every test file is mapped (:func:`all_test_files`),
a few at a time (:func:`chunks`: a stopped build resumes at the files not yet mapped).

A mutant then runs the tests, anywhere in the suite, that execute a line it changes
(:func:`select`), the cheaper first within a budget; a line run at import (outside any test,
or outside any function body) runs the tests that execute any line of its module, then those
of the test files that import it; a line nothing executes is reported as such (the mutant
survives without a run).

The C kernels' lines have maps of their own (``out/linemaps/c/``, :data:`C_FORMAT` in their
key), built by :mod:`benchmarks.mutation_cmap` in runs without coverage.py (gcov per test), the
first time a C mutant asks; ``for_files(..., language="c")``.  A C mutant's selection is the
same as a Python function body's.
"""
from __future__ import annotations

import contextlib
import gzip
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
#: What the key covers: every tree whose change may change which test runs which line.
KEYED = ("plant", "motor", "controller", "fmus", "scenarios", "parcosim", "kernels", "tests", "pyproject.toml")
#: Test files no mutant runs (the mutation tools' own, the sanitizer build of pristine C): not
#: in the map, and not in its key.
NOT_RUN = ("tests/benchmarks/test_mutation", "tests/kernels/test_sanitizers.py")
#: Not a test: coverage's context of lines run outside one (import, collection).
OUTSIDE = ""
#: The map's format, in its key: 2 = a test's subprocesses count as the test's (1: as no test's).
FORMAT = 2
#: The C maps' format (:mod:`benchmarks.mutation_cmap`), in their key: 1 = gcov per test, subprocesses included.
C_FORMAT = 1
#: A file of long runs (``pytest -m slow``): its tests run for a mutant only when no other covers it.
SLOW = re.compile(r"^pytestmark = .*pytest\.mark\.slow", re.M)
#: How many test files of a directory one map run takes (a stopped build loses at most one run).
CHUNK = 12


def pytest_command(copy: Path, *arguments) -> list:
    """``python -m pytest -q`` for a run in ``copy``: no cache written into it, and its root pinned to it (a copy
    inside another checkout would otherwise take that checkout's configuration and packages)."""
    return [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "--rootdir", str(copy), *arguments]


def key(root: Path = ROOT, commit: str = "HEAD", test_file: str | None = None, language: str = "python") -> str:
    """A hash of the committed files of :data:`KEYED` at ``commit`` (12 hex digits), of the
    tests' only ``test_file`` and the helpers (``tests/`` files not named ``test_*``), and of
    the map's format (:data:`FORMAT`, or :data:`C_FORMAT` for ``language`` "c"): what a test
    file's map depends on."""
    listing = subprocess.run(["git", "ls-tree", "-r", commit, "--", *KEYED], cwd=root, check=True,
                             capture_output=True, text=True).stdout.splitlines()
    kept = [line for line in listing if _keyed(line.split("\t", 1)[1], test_file)]
    form = f"format {FORMAT}" if language == "python" else f"c format {C_FORMAT}"
    return hashlib.sha1("\n".join([form, *kept]).encode()).hexdigest()[:12]


def head() -> str:
    """The tool's worktree's commit (a map records it)."""
    return subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True).stdout.strip()


def _keyed(path: str, test_file: str | None) -> bool:
    if path.startswith(NOT_RUN):
        return False
    if path.startswith("tests/") and Path(path).name.startswith("test_"):
        return test_file is None or path == test_file
    return True


def _product_file(measured: str, products: set) -> str | None:
    """The product file (relative to the root) that a measured path is a copy of."""
    parts = Path(measured).parts
    for k in range(len(parts) - 1):
        candidate = "/".join(parts[k:])
        if candidate in products:
            return candidate
    return None


def build(copy: Path, products: list, tests: list, out: Path, log=sys.stdout) -> dict:
    """Run ``tests`` (files, relative to ``copy``) in ``copy`` under coverage; write the map to
    ``out`` and return it."""
    import coverage

    work = Path(tempfile.mkdtemp(prefix="parcosim_linemap_"))
    rc = work / "coveragerc"
    data = work / ".coverage"
    # include, not source: coverage would walk a source folder (all of /tmp) for files not run; the copy
    # itself too, wherever it is (a copy outside the temporary folder was not measured at all)
    rc.write_text(f"[run]\nparallel = True\ninclude =\n    {tempfile.gettempdir()}/*\n    {copy.resolve()}/*\n"
                  f"data_file = {data}\n"
                  "context = ${PARCOSIM_TEST_CONTEXT-}\n")      # a subprocess's lines: the test that started it
    (work / "sitecustomize.py").write_text("import coverage\ncoverage.process_startup()\n")
    shutil.copy2(Path(__file__).with_name("mutation_timing.py"), work / "parcosim_mutation_timing.py")  # this tool's
    times = work / "times.json"
    env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1", COVERAGE_PROCESS_START=str(rc), COVERAGE_FILE=str(data),
               PARCOSIM_MUTATION_TIMES=str(times),
               PARCOSIM_CACHE=str(work / "cache"),
               PYTHONPATH=os.pathsep.join([str(copy), str(work), *_other_paths()]))
    command = pytest_command(copy, "-p", "parcosim_mutation_timing", "--cov", f"--cov-config={rc}",
                             "--cov-context=test", "--cov-report=", *tests)
    done = subprocess.run(command, cwd=copy, env=env, stdout=log, stderr=subprocess.STDOUT)
    covered = coverage.CoverageData(basename=str(data))
    covered.read()
    products_set = set(products)
    names, index = [], {}
    lines, outside = {}, {}
    for measured in covered.measured_files():
        product = _product_file(measured, products_set)
        if product is None:
            continue
        for line, contexts in covered.contexts_by_lineno(measured).items():
            for context in contexts:
                test = context.split("|")[0]
                if test == OUTSIDE:
                    outside.setdefault(product, set()).add(line)
                    continue
                if test not in index:
                    index[test] = len(names)
                    names.append(test)
                lines.setdefault(product, {}).setdefault(str(line), set()).add(index[test])
    timing = json.loads(times.read_text()) if times.exists() else {"tests": {}, "shared": {}, "failed": []}
    record = {"commit": head(),
              "returncode": done.returncode, "tests": names,
              "cost": [timing["tests"].get(name, {}).get("seconds", 0.0) for name in names],
              "slow": [timing["tests"].get(name, {}).get("slow", False) for name in names],
              "shared_of": [timing["tests"].get(name, {}).get("shared", []) for name in names],
              "shared": timing["shared"], "all_tests": timing["tests"], "failed": timing["failed"],
              "lines": {f: {line: sorted(ids) for line, ids in by.items()} for f, by in lines.items()},
              "outside": {f: sorted(ls) for f, ls in outside.items()}}
    out.parent.mkdir(parents=True, exist_ok=True)
    with gzip.open(out, "wt") as stream:
        json.dump(record, stream)
    shutil.rmtree(work, ignore_errors=True)
    return record


def merge(records: list) -> dict:
    """One map of the maps of disjoint sets of test files; a shared fixture costs the most any
    of them measured."""
    merged = {"returncode": max([r["returncode"] for r in records], default=0), "tests": [], "cost": [],
              "slow": [], "shared_of": [], "shared": {}, "all_tests": {}, "lines": {}, "outside": {}, "failed": []}
    for r in records:
        merged["failed"] += r.get("failed", [])
        offset = len(merged["tests"])
        for name in ("tests", "cost", "shared_of"):
            merged[name] += r[name]
        merged["slow"] += r.get("slow", [False] * len(r["tests"]))
        merged["all_tests"].update(r["all_tests"])
        for fixture, seconds in r["shared"].items():
            merged["shared"][fixture] = max(seconds, merged["shared"].get(fixture, 0.0))
        for f, by in r["lines"].items():
            into = merged["lines"].setdefault(f, {})
            for line, ids in by.items():
                into[line] = into.get(line, []) + [i + offset for i in ids]
        for f, lines in r["outside"].items():
            merged["outside"][f] = sorted(set(merged["outside"].get(f, [])) | set(lines))
    return merged


def shard_path(test_file: str, root: Path = ROOT, commit: str = "HEAD", language: str = "python") -> Path:
    """Where the map of one test file is kept: ``out/linemaps/<file>_<key>.json.gz``
    (:func:`key` of that file), its C map in ``out/linemaps/c/``."""
    folder = root / "out" / "linemaps" / ("c" if language == "c" else "")
    return folder / f"{test_file.replace('/', '__')}_{key(root, commit, test_file, language)}.json.gz"


def split(record: dict, test_file: str) -> dict:
    """The part of a map (of several test files' run) that is ``test_file``'s: its tests, the
    lines they execute; lines run outside any test and the shared fixtures' costs go with
    every part."""
    keep = [i for i, name in enumerate(record["tests"]) if name.split("::")[0] == test_file]
    new_index = {old: new for new, old in enumerate(keep)}
    lines = {}
    for f, by in record["lines"].items():
        for line, ids in by.items():
            mine = [new_index[i] for i in ids if i in new_index]
            if mine:
                lines.setdefault(f, {})[line] = mine
    own = {name: t for name, t in record["all_tests"].items() if name.split("::")[0] == test_file}
    return {"commit": record["commit"], "returncode": record["returncode"],
            "tests": [record["tests"][i] for i in keep], "cost": [record["cost"][i] for i in keep],
            "slow": [record.get("slow", [False] * len(record["tests"]))[i] for i in keep],
            "shared_of": [record["shared_of"][i] for i in keep], "shared": record["shared"], "all_tests": own,
            "failed": [t for t in record["failed"] if t.split("::")[0] == test_file], "lines": lines,
            "outside": record["outside"]}


def all_test_files(copy: Path) -> list:
    """Every test file of ``copy`` a mutant may run (relative to it; not :data:`NOT_RUN`)."""
    return sorted(str(p.relative_to(copy)) for p in (copy / "tests").rglob("test_*.py")
                  if not str(p.relative_to(copy)).startswith(NOT_RUN))


def chunks(copy: Path, test_files: list) -> list:
    """``test_files`` in the runs that map them: the files of one directory together, at most
    :data:`CHUNK` a run, the :data:`SLOW` files last, one a run."""
    slow = [f for f in test_files if SLOW.search((copy / f).read_text())]
    by_folder = {}
    for f in test_files:
        if f not in slow:
            by_folder.setdefault(str(Path(f).parent), []).append(f)
    runs = [files[k:k + CHUNK] for _, files in sorted(by_folder.items()) for k in range(0, len(files), CHUNK)]
    return runs + [[f] for f in sorted(slow)]


def for_files(copy: Path, products: list, test_files: list, lock_of=None, commit: str = "HEAD",
              log=subprocess.DEVNULL, language: str = "python") -> dict:
    """The map of ``test_files``; those not yet mapped are mapped (in ``copy``, unmutated, in
    the runs of :func:`chunks`: a run's session fixtures, such as the built FMUs, are made
    once) and each file's part is kept as soon as its run ends (:func:`shard_path` at
    ``commit``, the copy's).  ``lock_of(test_file)``: a lock held while that file's map is
    looked for and built (workers side by side build different files).  ``language`` "c":
    the map of the C kernels' lines (:func:`benchmarks.mutation_cmap.build`, a run of its own:
    the Python maps stay valid)."""
    from benchmarks import mutation_cmap

    locks = [lock_of(f) for f in sorted(set(test_files))] if lock_of else []
    for held in locks:
        held.acquire()
    try:
        missing = [f for f in test_files if not shard_path(f, commit=commit, language=language).exists()]
        runs = chunks(copy, missing)
        for n, run in enumerate(runs):
            start = time.monotonic()
            work = Path(tempfile.mkdtemp(prefix="parcosim_linemaps_"))
            if language == "c":
                record = mutation_cmap.build(copy, run, work / "all.json.gz", log)
            else:
                record = build(copy, products, run, work / "all.json.gz", log)
            for test_file in run:
                path = shard_path(test_file, commit=commit, language=language)
                path.parent.mkdir(parents=True, exist_ok=True)
                with gzip.open(path, "wt") as stream:
                    json.dump(split(record, test_file), stream)
            shutil.rmtree(work, ignore_errors=True)
            print(f"{language} map {n + 1}/{len(runs)}: {len(run)} files from {run[0]} ({len(record['tests'])} "
                  f"tests, {time.monotonic() - start:.0f} s)", flush=True)
        return merge([load(shard_path(f, commit=commit, language=language)) for f in test_files])
    finally:
        for held in locks:
            held.release()


def _other_paths() -> list:
    """``$PYTHONPATH`` less the worktree (a copy's run must import the copy's modules, and so
    must its subprocesses)."""
    return [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep)
            if p and Path(p).resolve() != ROOT]


def load(path: Path) -> dict:
    with gzip.open(path, "rt") as stream:
        return json.load(stream)


def cost(record: dict, tests: list) -> float:
    """Seconds ``tests`` (node ids) took in the map's run: their own and their shared fixtures'."""
    own = record["all_tests"]
    shared = {s for t in tests for s in own.get(t, {}).get("shared", [])}
    return sum(own.get(t, {}).get("seconds", 0.0) for t in tests) + sum(record["shared"].get(s, 0.0) for s in shared)


def function_lines(text: str) -> set:
    """The lines of a Python file's function bodies: run when the function is called, not at
    import (a ``def``'s decorators, default values and the module's other lines are)."""
    import ast

    lines = set()
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            lines.update(range(node.body[0].lineno, node.end_lineno + 1))
    return lines


def c_function_lines(text: str, line: int) -> range:
    """The lines of the top-level brace block (a C function's body) that holds ``line``; empty
    outside any.  Braces in comments, strings and character literals are not counted."""
    code = re.sub(r"/\*.*?\*/|//[^\n]*|\"(?:\\.|[^\"\\\n])*\"|'(?:\\.|[^'\\\n])*'",
                  lambda m: re.sub(r"[^\n]", " ", m.group()), text, flags=re.S)
    depth, start = 0, None
    for number, row in enumerate(code.split("\n"), start=1):
        for char in row:
            if char == "{":
                depth += 1
                if depth == 1:
                    start = number
            elif char == "}" and depth:
                depth -= 1
                if depth == 0 and start <= line <= number:
                    return range(start, number + 1)
    return range(0)


def _within(record: dict, ids: list, budget: float) -> tuple:
    """The tests of ``ids`` (in that order) whose measured seconds, with the shared fixtures
    they add, fit in ``budget``; the first test not marked slow is taken whatever it costs."""
    own, chosen, shared, total = record["all_tests"], [], set(), 0.0
    slow = record.get("slow") or [False] * len(record["tests"])
    for i in ids:
        name = record["tests"][i]
        new = set(own.get(name, {}).get("shared", [])) - shared
        extra = own.get(name, {}).get("seconds", 0.0) + sum(record["shared"].get(s, 0.0) for s in new)
        if (chosen or slow[i]) and total + extra > budget:
            continue
        chosen.append(name)
        shared |= new
        total += extra
    return chosen, round(total, 2)


def _full_cost(record: dict, i: int) -> float:
    """Test ``i``'s measured seconds with its shared fixtures' (a 0.01 s test of a module whose fixture
    builds a package for 8 s costs 8 s when it runs first)."""
    shared = record.get("shared_of") or [[]] * len(record["tests"])
    return record["cost"][i] + sum(record["shared"].get(s, 0.0) for s in shared[i])


def _order(record: dict, tiers: list) -> list:
    """The tests of ``tiers`` (sets of indices, the first tier first), each once: in each tier
    the cheaper first, counting their shared fixtures; the tests marked slow only when no tier has
    another, then the cheaper."""
    slow = record.get("slow") or [False] * len(record["tests"])
    seen, quick, slow_ones = set(), [], []
    for tier in tiers:
        for i in sorted(tier - seen, key=lambda i: (_full_cost(record, i), record["tests"][i])):
            (slow_ones if slow[i] else quick).append(i)
        seen |= tier
    return quick or sorted(slow_ones, key=lambda i: _full_cost(record, i))


def select(record: dict, file: str, first: int, last: int, budget: float, at_import: bool = False,
           importers: tuple = (), enclosing: range = range(0)) -> dict:
    """The tests to run for a change of ``file``'s lines ``first``..``last``.

    ``{"tests": node ids, "covering": how many tests execute the lines, "cost": the
    selection's measured seconds, "kind": "coverage", "import" or "none"}``.  A line some test
    executes (itself or in a process it started): those tests.  A line run at import
    (``at_import``, or run outside any test; a module-level line is seen by every test after
    the import): the tests that execute it, then those that execute any line of ``file``, then
    those of ``importers`` (the test files that import its module).  In each group the cheaper
    first, within ``budget`` seconds (:func:`_within`); tests that fail unmutated never; tests
    marked slow only when no other would run.  ``tests == []``: nothing executes the lines.
    A C line no test executes (``kind`` "enclosing"): the tests that execute a line of
    ``enclosing``, its function (gcov gives a call of an always-inlined function no line of its own).
    """
    by_line = record["lines"].get(file, {})
    failing = set(record.get("failed", ()))
    usable = {i for i, name in enumerate(record["tests"]) if name not in failing}
    ids = {i for line in range(first, last + 1) for i in by_line.get(str(line), ())} & usable
    outside = set(record["outside"].get(file, ()))
    if at_import or any(line in outside for line in range(first, last + 1)):
        users = {i for line_ids in by_line.values() for i in line_ids} & usable
        importing = {i for i in usable if record["tests"][i].split("::")[0] in set(importers)}
        tiers, kind = [ids, users, importing], "import"
    elif not ids and enclosing:
        tiers, kind = [{i for line in enclosing for i in by_line.get(str(line), ())} & usable], "enclosing"
    else:
        tiers, kind = [ids], "coverage"
    order = _order(record, tiers)
    if not order:
        return {"tests": [], "covering": 0, "cost": 0.0, "kind": "none"}
    chosen, total = _within(record, order, budget)
    return {"tests": chosen, "covering": len(ids), "cost": total, "kind": kind}
