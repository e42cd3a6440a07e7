"""A pytest plugin that records what each test costs, for :mod:`benchmarks.mutation_map`.

Loaded with ``-p benchmarks.mutation_timing`` when the line -> tests map is built; it writes
the JSON file named by ``$PARCOSIM_MUTATION_TIMES`` at the session's end:

``tests``     node id -> {"seconds": its setup, call and teardown less the shared fixtures it
              set up, "shared": the shared fixtures it uses, "slow": whether it is marked slow}
``shared``    key of a fixture of wider scope than a function (``scope:argname``, with the
              module for a module-scoped one) -> the seconds its setup took

``failed``    node ids of the tests that failed or errored (the map's run is on the unmutated
              tree: a mutant does not run them)

``gcov``      (with ``$PARCOSIM_MUTATION_GCOV``, a C map's run: :mod:`benchmarks.mutation_cmap`)
              n -> the node id of the n-th test run: the folder ``$PARCOSIM_MUTATION_GCOV/n``
              holds the C line counts of that test and of the processes it started

While a test runs, ``$PARCOSIM_TEST_CONTEXT`` holds its node id: a process it starts inherits
it, and the map's coverage configuration takes it as the static context of that process
(``[run] context = ${PARCOSIM_TEST_CONTEXT-}``), so the lines a test's subprocesses execute
count as that test's.

A subset of the tests then costs the sum of its tests' own seconds and of the shared fixtures
they use (each once), whatever test of the subset sets a shared fixture up first.
"""
from __future__ import annotations

import ctypes
import json
import os
import time

import pytest

_TESTS: dict = {}
_SHARED: dict = {}
_FAILED: set = set()
_DURING: list = []       # the shared fixtures' seconds spent inside the current test's phases
#: The environment variable a test's subprocesses read their coverage context from.
CONTEXT = "PARCOSIM_TEST_CONTEXT"
#: A C map's run: the folder of the per-test gcov folders, and the test number of each.
GCOV = os.environ.get("PARCOSIM_MUTATION_GCOV")
_GCOV_TESTS: dict = {}
_HOOKS = ctypes.CDLL(os.environ["PARCOSIM_KERNELS_LIB"]) if GCOV else None
if GCOV:
    os.environ["GCOV_PREFIX"] = os.path.join(GCOV, "outside")       # collection: no test's


def _key(fixturedef, request) -> str:
    module = getattr(request, "module", None)
    where = module.__name__ if fixturedef.scope == "module" and module is not None else ""
    return f"{fixturedef.scope}:{where}:{fixturedef.argname}"


@pytest.hookimpl(hookwrapper=True)
def pytest_fixture_setup(fixturedef, request):
    start = time.perf_counter()
    yield
    if fixturedef.scope != "function":
        seconds = time.perf_counter() - start
        _SHARED[_key(fixturedef, request)] = round(seconds, 3)
        _DURING.append(seconds)


def _shared_of(item) -> list:
    found = []
    info = getattr(item, "_fixtureinfo", None)
    for name in getattr(item, "fixturenames", ()):
        defs = info.name2fixturedefs.get(name, ()) if info is not None else ()
        if defs and defs[-1].scope != "function":
            scope = defs[-1].scope
            found.append(f"{scope}:{item.module.__name__ if scope == 'module' else ''}:{name}")
    return found


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    _DURING.clear()
    os.environ[CONTEXT] = item.nodeid
    if GCOV:
        number = str(len(_GCOV_TESTS))
        _GCOV_TESTS[number] = item.nodeid
        os.environ["GCOV_PREFIX"] = os.path.join(GCOV, number)    # this process's dump, its children's exits
        _HOOKS.pc_coverage_reset()
    start = time.perf_counter()
    try:
        yield
    finally:
        os.environ.pop(CONTEXT, None)
        if GCOV:
            _HOOKS.pc_coverage_dump()
            os.environ["GCOV_PREFIX"] = os.path.join(GCOV, "outside")
    own = time.perf_counter() - start - sum(_DURING)
    _TESTS[item.nodeid] = {"seconds": round(max(own, 0.0), 3), "shared": _shared_of(item),
                           "slow": item.get_closest_marker("slow") is not None}


def pytest_runtest_logreport(report):
    if report.failed:
        _FAILED.add(report.nodeid)


def pytest_sessionfinish(session):
    path = os.environ.get("PARCOSIM_MUTATION_TIMES")
    if path:
        with open(path, "w") as out:
            json.dump({"tests": _TESTS, "shared": _SHARED, "failed": sorted(_FAILED), "gcov": _GCOV_TESTS}, out)
