"""The mutation campaign's C map and its loud failures (benchmarks/mutation_cmap.py,
benchmarks/mutation_run.py; session 41): a C mutant runs the tests that execute its line, in process
or in a process they start, and a run that fails loudly (the tests no longer collect, a crash) counts
as killed only when the same tests pass on the unmutated tree.  Real builds and pytest runs of
made-up projects in ``tmp_path`` (a few seconds)."""
from __future__ import annotations

import json
import shutil
import sys
import textwrap

import pytest

from benchmarks import mutation_cmap as cm
from benchmarks import mutation_c as mc
from benchmarks import mutation_map as mm
from benchmarks import mutation_py as mp
from benchmarks import mutation_run as mr

TINY = "int f(int x);\n\nint f(int x)\n{\n    if (x > 0) {\n        return 2 * x;\n    }\n    return -x;\n}\n"
POSITIVE, CHILD, NEITHER = (f"tests/test_t.py::{name}" for name in ("test_positive", "test_negative_in_a_child",
                                                                   "test_no_kernel"))


def _own_config(project):
    """A made-up project's own pytest configuration: without it, pytest takes the first one above it (this
    repository's, when the temporary folder is inside a checkout) and imports the checkout's packages."""
    (project / "pytest.ini").write_text("[pytest]\n")


@pytest.fixture(scope="module")
def c_project(tmp_path_factory):
    """A made-up project: kernels/src/tiny.c and three tests that load it by ``$PARCOSIM_KERNELS_LIB``:
    one calls it in process (line 6), one in a child process (line 8), one not at all; and its C map."""
    if not shutil.which("gcov"):
        pytest.skip("gcov is not installed")
    tmp_path = tmp_path_factory.mktemp("c_project")
    (tmp_path / "kernels" / "src").mkdir(parents=True)
    (tmp_path / "kernels" / "src" / "tiny.c").write_text(TINY)
    _own_config(tmp_path)
    (tmp_path / "tests").mkdir()
    (tmp_path / "tests" / "test_t.py").write_text(textwrap.dedent(f'''\
        import ctypes, os, subprocess

        lib = ctypes.CDLL(os.environ["PARCOSIM_KERNELS_LIB"])


        def test_positive():
            assert lib.f(3) == 6


        def test_negative_in_a_child():
            code = "import ctypes, os; assert ctypes.CDLL(os.environ['PARCOSIM_KERNELS_LIB']).f(-3) == 3"
            subprocess.run([{sys.executable!r}, "-c", code], check=True)


        def test_no_kernel():
            assert True
        '''))
    return tmp_path, cm.build(tmp_path, ["tests/test_t.py"], tmp_path / "m.json.gz", log=None)


def test_a_c_line_maps_to_the_tests_that_execute_it_in_process_or_in_a_child(c_project):
    """Catches a C map that loses a child process's lines or gives them to no test or every test, one
    that gives the lines run at collection (the library loaded at import) to the first test, one that
    keeps the counts of one test for the next (no reset), or a C selection that runs tests that never
    execute the line or none for a line some test executes."""
    _, record = c_project
    assert record["returncode"] == 0 and record["failed"] == []
    by_line = record["lines"]["kernels/src/tiny.c"]
    named = {line: sorted(record["tests"][i] for i in ids) for line, ids in by_line.items()}
    assert named["6"] == [POSITIVE] and named["8"] == [CHILD]
    assert named["5"] == sorted([POSITIVE, CHILD])
    assert NEITHER not in record["tests"] and NEITHER in record["all_tests"]   # its cost is known all the same
    assert "1" not in named and "7" not in named          # a declaration, a closing brace: no code of their own
    assert mm.select(record, "kernels/src/tiny.c", 8, 8, 60.0)["tests"] == [CHILD]
    both = mm.select(record, "kernels/src/tiny.c", 5, 5, 60.0)
    assert sorted(both["tests"]) == sorted([POSITIVE, CHILD]) and both["kind"] == "coverage"
    assert mm.select(record, "kernels/src/tiny.c", 1, 1, 60.0)["kind"] == "none"


def test_a_c_mutant_runs_its_line_s_tests_against_its_own_build(c_project):
    """Catches a C mutant run against the unmutated library, or reported killed or survived the wrong
    way: the mutant of line 6 fails test_positive; the mutant of line 8 with a selection of a test
    that does not execute it survives."""
    c_project, record = c_project
    doubled = mc.Mutant("tiny.c", 6, 15, "constant", "2", "4")
    chosen = mm.select(record, "kernels/src/tiny.c", 6, 6, 60.0)
    killed = mr.run_c(c_project, doubled, chosen, 30.0, 1.0)
    assert killed["outcome"] == "killed" and killed["killed_by"] == "test" and killed["failed"] == [POSITIVE]
    sign = mc.Mutant("tiny.c", 8, 11, "drop", "-x", "x")
    assert TINY.split("\n")[7][11:13] == "-x"
    unseen = mr.run_c(c_project, sign, {"tests": [POSITIVE], "cost": 0.1}, 30.0, 1.0)
    assert unseen["outcome"] == "survived"
    none = mr.run_c(c_project, sign, {"tests": [], "cost": 0.0, "note": "no test executes the line"}, 30.0, 1.0)
    assert none == {"outcome": "survived", "seconds": 0.0, "note": "no test executes the line"}


def test_pytest_s_exit_statuses_map_to_outcomes_and_loud_kinds():
    """Catches a loud failure (collection, crash, internal error) taken for a test's failure or a
    pass, or a test's failure or a pass taken for a loud failure."""
    assert [mr.loud(code) for code in (0, 1, 2, 5)] == [None] * 4
    assert (mr.loud(3), mr.loud(4), mr.loud(-11), mr.loud(-6)) == ("internal error", "collection", "crash", "crash")
    loud = {"outcome": "loud", "killed_by": "crash", "returncode": -11}
    asked = []

    def pristine(outcome, returncode=None):
        return lambda collect_only: asked.append(collect_only) or {"outcome": outcome, "returncode": returncode}

    assert mr.decide_loud(loud, pristine("survived")) == dict(loud, outcome="killed")
    assert mr.decide_loud(loud, pristine("loud", -11)) == dict(loud, outcome="baseline failure",
                                                               baseline_returncode=-11)
    uncollected = {"outcome": "loud", "killed_by": "collection", "returncode": 4}
    assert mr.decide_loud(uncollected, pristine("survived", 0)) == dict(uncollected, outcome="killed")
    assert asked == [False, False, True]          # a crash runs the tests again, a collection failure collects them
    plain = {"outcome": "survived"}
    assert mr.decide_loud(plain, lambda collect_only: pytest.fail("a quiet run was run again")) is plain


@pytest.fixture
def py_project(tmp_path):
    """A made-up project: plant/x.py (``VALUE = 2`` at import) and its tests, one of which crashes."""
    (tmp_path / "plant").mkdir()
    _own_config(tmp_path)
    (tmp_path / "plant" / "__init__.py").write_text("")
    (tmp_path / "plant" / "x.py").write_text("VALUE = 2\n\n\ndef f():\n    return VALUE\n")
    (tmp_path / "tests").mkdir()
    (tmp_path / "tests" / "test_x.py").write_text(
        "import os\nimport signal\n\nfrom plant import x\n\n\ndef test_f():\n    assert x.f() > 0\n\n\n"
        "def test_crash():\n    os.kill(os.getpid(), signal.SIGSEGV)\n")
    return tmp_path


@pytest.mark.parametrize("after, test, outcome, killed_by", [
    ("-2", "test_f", "killed", "test"),                          # a failing test
    ("2 / 0", "test_f", "killed", "collection"),                 # the module no longer imports: exit status 4
    ("3", "test_crash", "baseline failure", "crash"),            # crashes unmutated too: counted neither way
])
def test_a_loud_failure_is_a_kill_only_when_the_unmutated_tree_passes(py_project, after, test, outcome, killed_by):
    """Catches a mutant that breaks its module's import (its tests no longer collect) left uncounted or
    counted as survived, or a run that fails loudly on the unmutated tree too counted as a kill."""
    mutant = mp.PyMutant("plant/x.py", 1, 8, 1, 9, "constant", "2", after)
    result = mr.run_python(py_project, mutant, {"tests": [f"tests/test_x.py::{test}"], "cost": 0.1}, 30.0, 1.0)
    assert result["outcome"] == outcome and result.get("killed_by") == killed_by
    assert (py_project / "plant" / "x.py").read_text().startswith("VALUE = 2\n")       # put back
    if outcome == "baseline failure":
        assert result["baseline_returncode"] == result["returncode"] == -11


def test_a_rerun_of_one_language_or_one_outcome_carries_the_others(tmp_path, monkeypatch):
    """Catches ``--language c`` re-running Python mutants (or the reverse), or ``--outcomes error``
    re-running survivors: the re-score of one part of a sample would cost the whole sample's runs."""
    from tests.benchmarks.test_mutation_select import _campaign_file
    source, _ = _campaign_file(tmp_path, monkeypatch)
    lines = source.read_text().splitlines()
    for k in range(6):          # 1 (survived) and 4 (error) are C
        entry = json.loads(lines[k + 1])
        lines[k + 1] = json.dumps(dict(entry, language="c" if k in (1, 4) else "python"))
    source.write_text("\n".join(lines) + "\n")
    ran = []
    monkeypatch.setattr(mr, "_run_all", lambda chosen, pending, *rest: ran.append(list(pending)))
    monkeypatch.setattr(mm, "key", lambda *a, **k: "key")
    mr.rerun(source, tmp_path / "c.jsonl", language="c")
    mr.rerun(source, tmp_path / "errors.jsonl", outcomes=("error",))
    mr.rerun(source, tmp_path / "py.jsonl", language="python")
    assert ran == [[1, 4], [4], [2, 5]]
    header, done = mr.read_results(tmp_path / "c.jsonl")
    assert header["language"] == "c" and sorted(done) == [0, 2, 3, 5] and all(m["carried"] for m in done.values())
