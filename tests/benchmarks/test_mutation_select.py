"""benchmarks/mutation_map.py's selection on small made-up maps (and one real map of a made-up
project): a mutant runs the tests, of any test file, that execute its lines, in process or in a
process they start; a line run at import runs its module's tests, then its importers'; the
cheaper first within the budget; slow tests only when no other covers the line; a re-run of an
earlier campaign runs its survivors again and keeps its kills."""
from __future__ import annotations

import json
import sys
import textwrap
from pathlib import Path

import pytest

from benchmarks import mutation_map as mm
from benchmarks import mutation_py as mp
from benchmarks import mutation_run as mr

FAR = "tests/far/test_far.py"          # a test file that does not import the module it executes
NEAR = "tests/near/test_near.py"
SLOW = "tests/slow/test_slow.py"


def _record(slow=(False, False, False, False, True), failed=()):
    """A map of five tests: a cheap far one and a dear near one on line 10, one that uses an FMU
    fixture of 100 s on line 30, a near one that executes no line of plant/x.py, a slow one alone
    on line 40."""
    tests = [f"{FAR}::test_cheap", f"{NEAR}::test_dear", f"{FAR}::test_fmu", f"{NEAR}::test_other",
             f"{SLOW}::test_long"]
    seconds = [1.0, 50.0, 2.0, 0.5, 200.0]
    shared = [[], [], ["session::built_fmus"], [], []]
    return {"tests": tests, "cost": seconds, "slow": list(slow), "shared": {"session::built_fmus": 100.0},
            "shared_of": shared, "failed": list(failed),
            "all_tests": {t: {"seconds": s, "shared": f} for t, s, f in zip(tests, seconds, shared)},
            "lines": {"plant/x.py": {"10": [0, 1, 2], "11": [1], "30": [2], "40": [4]},
                      "plant/y.py": {"5": [3]}},
            "outside": {"plant/x.py": [1, 2, 20]}}


def test_a_line_runs_the_tests_that_execute_it_from_any_test_file_cheapest_first_within_the_budget():
    """Catches a selection cut to the module's near test files (the far file's tests execute the
    line), one that ignores the budget, counts a shared fixture twice, or orders tests otherwise
    (by their own seconds alone: test_fmu's 2 s need its fixture's 100 s, so test_dear's 50 s go first)."""
    record = _record()
    assert mm.cost(record, record["tests"][2:3]) == 102.0                 # a shared fixture once, with its test
    every = mm.select(record, "plant/x.py", 10, 10, budget=1000.0)
    assert every["tests"] == [f"{FAR}::test_cheap", f"{NEAR}::test_dear", f"{FAR}::test_fmu"]
    assert every["covering"] == 3 and every["cost"] == 153.0 and every["kind"] == "coverage"
    cut = mm.select(record, "plant/x.py", 10, 10, budget=60.0)            # the fixture's 100 s do not fit
    assert cut["tests"] == [f"{FAR}::test_cheap", f"{NEAR}::test_dear"] and cut["cost"] == 51.0
    assert mm.select(record, "plant/x.py", 11, 11, budget=0.0)["tests"] == [f"{NEAR}::test_dear"]  # the first always
    assert mm.select(record, "plant/x.py", 29, 31, budget=60.0)["tests"] == [f"{FAR}::test_fmu"]   # a span
    assert mm.select(record, "plant/x.py", 50, 50, budget=60.0) == {"tests": [], "covering": 0, "cost": 0.0,
                                                                   "kind": "none"}
    assert mm.select(record, "plant/z.py", 1, 1, budget=60.0)["tests"] == []


def test_a_slow_test_runs_only_when_no_other_covers_the_line_and_only_within_the_budget():
    """Catches slow tests run beside quicker ones that cover the line, left out when they are the only
    ones, or run past the budget (the first-test exemption is for the quick ones)."""
    record = _record(slow=(False, True, False, False, True))
    assert mm.select(record, "plant/x.py", 10, 10, 1000.0)["tests"] == [f"{FAR}::test_cheap", f"{FAR}::test_fmu"]
    assert mm.select(record, "plant/x.py", 11, 11, 1000.0)["tests"] == [f"{NEAR}::test_dear"]    # slow, alone
    assert mm.select(record, "plant/x.py", 40, 40, 300.0)["tests"] == [f"{SLOW}::test_long"]
    over = mm.select(record, "plant/x.py", 40, 40, 100.0)
    assert over["tests"] == [] and over["covering"] == 1 and over["kind"] == "coverage"


def test_a_line_run_at_import_runs_its_tests_then_the_modules_then_the_importers():
    """Catches an import-time line (a module-level constant, a default value) that runs only the one test
    that happened to import the module first, nothing, or every test file whole; and tests that fail on
    the unmutated tree selected."""
    record = _record(failed=[f"{FAR}::test_fmu"])
    at_import = mm.select(record, "plant/x.py", 20, 20, 1000.0, importers=(NEAR,))     # run outside any test
    assert at_import["kind"] == "import" and at_import["covering"] == 0
    assert at_import["tests"] == [f"{FAR}::test_cheap", f"{NEAR}::test_dear", f"{NEAR}::test_other"]
    first = mm.select(record, "plant/x.py", 11, 11, 1000.0, at_import=True, importers=(NEAR,))
    assert first["tests"][0] == f"{NEAR}::test_dear" and first["covering"] == 1      # its own test first
    assert mm.select(record, "plant/x.py", 20, 20, 1000.0)["tests"] == [f"{FAR}::test_cheap", f"{NEAR}::test_dear"]
    assert mm.select(record, "plant/q.py", 3, 3, 1000.0, at_import=True, importers=(NEAR,))["tests"] == \
        [f"{NEAR}::test_other", f"{NEAR}::test_dear"]                  # executed by none: the importers' tests
    assert mm.select(record, "plant/x.py", 20, 20, 10.0, importers=(NEAR,))["tests"] == \
        [f"{FAR}::test_cheap", f"{NEAR}::test_other"]                  # within the budget


def test_function_bodies_run_when_called_and_the_rest_at_import():
    """Catches a default value, a decorator or a module constant taken for a line some test calls (it is
    seen by every test after the import), or a function body taken for an import-time line."""
    text = textwrap.dedent('''\
        LIMIT = 2.0


        @wrap(3)
        def f(a, b=LIMIT * 2):
            c = a + b
            return c


        class K:
            x = 1

            def g(self):
                return self.x
        ''')
    assert mm.function_lines(text) == {6, 7, 14}


def test_the_maps_are_built_a_folder_at_a_time_and_the_slow_files_last(tmp_path, monkeypatch):
    """Catches a build that maps every file in one run (a stop loses all of it), mixes folders in a run,
    or runs a slow file with quick ones."""
    monkeypatch.setattr(mm, "CHUNK", 2)
    files = ["tests/a/test_1.py", "tests/a/test_2.py", "tests/a/test_3.py", "tests/b/test_4.py", "tests/a/test_5.py"]
    for f in files:
        (tmp_path / f).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / f).write_text("pytestmark = pytest.mark.slow\n" if f.endswith("5.py") else "x = 1\n")
    assert mm.chunks(tmp_path, files) == [["tests/a/test_1.py", "tests/a/test_2.py"], ["tests/a/test_3.py"],
                                          ["tests/b/test_4.py"], ["tests/a/test_5.py"]]


def test_a_line_run_only_in_a_child_process_counts_as_the_test_that_started_it(tmp_path):
    """Catches the map losing a subprocess's lines (a CLI test, the hostile worker, an FMU loaded in a
    child) or giving them to no test or to every test: the real map of a made-up project, under coverage."""
    pytest.importorskip("pytest_cov")
    (tmp_path / "plant").mkdir()
    (tmp_path / "tests").mkdir()
    (tmp_path / "plant" / "__init__.py").write_text("")
    (tmp_path / "plant" / "x.py").write_text("def f(a):\n    b = a + 1\n    return b\n\n\ndef g(a):\n    return 2 * a\n")
    (tmp_path / "tests" / "test_x.py").write_text(textwrap.dedent(f'''\
        import subprocess
        from plant import x


        def test_in_process():
            assert x.g(2) == 4


        def test_in_a_child():
            subprocess.run([{sys.executable!r}, "-c", "from plant import x; x.f(1)"], check=True)
        '''))
    record = mm.build(tmp_path, ["plant/x.py", "plant/__init__.py"], ["tests/test_x.py"], tmp_path / "m.json.gz")
    assert record["returncode"] == 0
    named = {line: sorted(record["tests"][i] for i in ids) for line, ids in record["lines"]["plant/x.py"].items()}
    assert named["2"] == named["3"] == ["tests/test_x.py::test_in_a_child"]
    assert named["7"] == ["tests/test_x.py::test_in_process"]
    assert mm.select(record, "plant/x.py", 2, 2, 60.0)["tests"] == ["tests/test_x.py::test_in_a_child"]
    assert record["slow"] == [False, False]


def test_a_run_of_several_test_files_splits_into_each_files_map_and_merges_back():
    """Catches a split or merge of the line map that loses lines, tests or their slow marks."""
    record = dict(_record(slow=(False, True, False, False, True)), commit="c", returncode=0)
    near, far = mm.split(record, NEAR), mm.split(record, FAR)
    assert far["tests"] == [f"{FAR}::test_cheap", f"{FAR}::test_fmu"] and far["slow"] == [False, False]
    assert near["lines"] == {"plant/x.py": {"10": [0], "11": [0]}, "plant/y.py": {"5": [1]}}
    assert near["slow"] == [True, False]
    merged = mm.merge([far, near, mm.split(record, SLOW)])
    assert sorted(merged["tests"]) == sorted(record["tests"])
    slow_of = dict(zip(merged["tests"], merged["slow"]))
    assert slow_of == dict(zip(record["tests"], record["slow"]))
    assert {f: {line: sorted(merged["tests"][i] for i in ids) for line, ids in by.items()}
            for f, by in merged["lines"].items()} == \
        {f: {line: sorted(record["tests"][i] for i in ids) for line, ids in by.items()}
         for f, by in record["lines"].items()}


def _campaign_file(tmp_path, monkeypatch):
    """A recorded campaign of a made-up pool: 6 mutants, outcomes killed, survived, timeout,
    not viable, error, survived."""
    from tests.benchmarks.test_mutation_py import SNIPPET
    monkeypatch.setattr(mp, "line_count", lambda name: 100)
    pool = {"a.py": mp.mutants_of_python("a.py", SNIPPET), "b.py": mp.mutants_of_python("b.py", SNIPPET)}
    monkeypatch.setattr(mp, "pool_by_file", lambda: pool)
    drawn = mp.draw(pool, 7, 6)
    header = {"seed": 7, "sample": 6, "commit": "0" * 40, "drawn": [name for name, _ in drawn], "lines": {}}
    outcomes = ["killed", "survived", "timeout", "not viable", "error", "survived"]
    source = tmp_path / "old.jsonl"
    source.write_text("\n".join(json.dumps(line) for line in [{"header": header}] + [
        {"index": k, "file": name, "line": m.line, "operator": m.operator, "after": m.after, "outcome": outcomes[k]}
        for k, (name, m) in enumerate(drawn)]) + "\n")
    return source, drawn


def test_a_rerun_runs_the_survivors_timeouts_and_errors_again_keeps_the_kills_and_resumes(tmp_path, monkeypatch):
    """Catches a re-run that runs killed mutants again, drops them from the new file (the score would
    lose them), leaves an old loud failure (``error``) undecided, writes over the file it re-runs, or
    runs a mutant twice when resumed."""
    source, drawn = _campaign_file(tmp_path, monkeypatch)
    ran = []

    def run_all(chosen, pending, header, results, done, *rest):
        ran.append(list(pending))
        with results.open("a") as out:
            for k in pending[:1]:          # stopped after one
                out.write(json.dumps({"index": k, "outcome": "killed"}) + "\n")

    monkeypatch.setattr(mr, "_run_all", run_all)
    monkeypatch.setattr(mm, "key", lambda *a, **k: "key")
    with pytest.raises(ValueError, match="to a new file"):
        mr.rerun(source, source)
    new = tmp_path / "new.jsonl"
    mr.rerun(source, new, budget=60.0)
    assert ran == [[1, 2, 4, 5]]
    header, done = mr.read_results(new)
    assert header["rerun_of"] == str(source) and header["budget_seconds"] == 60.0 and header["drawn"]
    assert {k: m["outcome"] for k, m in done.items()} == {0: "killed", 1: "killed", 3: "not viable"}
    assert all(done[k]["carried"] for k in (0, 3))
    mr.rerun(source, new)
    assert ran[-1] == [2, 4, 5]
    assert source.read_text().count("\n") == 7                         # the file re-run is untouched


def test_a_rerun_of_another_draw_is_refused(tmp_path, monkeypatch):
    """Catches a re-run whose tree draws other mutants than the file recorded (a file moved or changed):
    it would run other mutants under the recorded indices."""
    source, drawn = _campaign_file(tmp_path, monkeypatch)
    lines = source.read_text().splitlines()
    entry = json.loads(lines[2])
    lines[2] = json.dumps(dict(entry, line=entry["line"] + 1))
    source.write_text("\n".join(lines) + "\n")
    monkeypatch.setattr(mr, "_run_all", lambda *a: pytest.fail("ran a mutant of another draw"))
    with pytest.raises(ValueError, match="this tree draws"):
        mr.rerun(source, tmp_path / "new.jsonl")


def test_the_slow_files_are_mapped_only_for_a_mutant_no_other_test_would_run(tmp_path, monkeypatch):
    """Catches slow files mapped (minutes each) for a mutant that quicker tests cover, a mutant whose
    only covering tests are in slow files left with no test, or one whose slow tests are all over the
    budget stopping the campaign (seed 3601's re-run: a KeyError for its missing note)."""
    (tmp_path / "plant").mkdir()
    (tmp_path / "plant" / "x.py").write_text("\n".join(f"def f{k}():\n    return {k}" for k in range(30)) + "\n")
    for f, text in ((FAR, "x = 1\n"), (NEAR, "x = 1\n"), (SLOW, "pytestmark = pytest.mark.slow\n")):
        (tmp_path / f).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / f).write_text(text)
    asked = []

    def for_files(copy, products, files, *rest, **options):
        asked.append(sorted(files))
        return mm.merge([mm.split(dict(_record(), commit="c", returncode=0), f) for f in files])

    monkeypatch.setattr(mm, "for_files", for_files)
    monkeypatch.setattr(mr, "_MAPS", {})
    mutant = mp.PyMutant("plant/x.py", 10, 4, 10, 10, "constant", "1", "2")
    chosen = mr.select(tmp_path, "plant/x.py", mutant, [], 1000.0, slow_maps=False)
    assert chosen["tests"][0] == f"{FAR}::test_cheap" and asked == [sorted([FAR, NEAR])]
    alone = mp.PyMutant("plant/x.py", 40, 4, 40, 10, "constant", "1", "2")
    with pytest.raises(mr.NeedsSlowMaps):
        mr.select(tmp_path, "plant/x.py", alone, [], 1000.0, slow_maps=False)
    assert mr.select(tmp_path, "plant/x.py", alone, [], 1000.0)["tests"] == [f"{SLOW}::test_long"]
    assert asked[-1] == sorted([FAR, NEAR, SLOW])
    over = mr.select(tmp_path, "plant/x.py", alone, [], 100.0)     # its one slow test costs more
    assert over["tests"] == [] and "marked slow" in over["note"]
    path = tmp_path / "plant" / "x.py"
    before = path.read_text()
    real = mp.PyMutant("plant/x.py", 40, 11, 40, 13, "constant", "19", "20")   # line 40: "    return 19"
    assert mr.run_python(tmp_path, real, over, 1.0, 1.0) == {"outcome": "survived", "seconds": 0.0,
                                                             "note": over["note"]}
    assert path.read_text() == before       # nothing was written: no test to run


C_TEXT = """\
/* a comment with a brace { that opens nothing */
static const double table[2] = {1.0, 2.0};
INLINE void helper(double *x)
{
    *x += 1.0;   /* '}' in a comment */
}
void step(double *x)
{
    const char *brace = "}{";
    helper(x);
    if (*x > 3.0) {
        *x = 3.0;
    }
}
"""


def test_a_c_line_is_placed_in_the_function_that_holds_it_whatever_braces_its_comments_and_strings_hold():
    """Catches braces counted inside comments or strings (the block would end early or never), an
    initializer taken for no block, or the block of another function."""
    assert mm.c_function_lines(C_TEXT, 10) == range(8, 15)           # helper(x); in step's body
    assert mm.c_function_lines(C_TEXT, 12) == range(8, 15)           # a nested block: still step's
    assert mm.c_function_lines(C_TEXT, 5) == range(4, 7)
    assert mm.c_function_lines(C_TEXT, 2) == range(2, 3)             # the initializer's own braces
    assert mm.c_function_lines(C_TEXT, 3) == range(0)                # a signature, outside any block
    assert mm.c_function_lines(C_TEXT, 1) == range(0)


def test_a_c_line_gcov_counts_for_no_test_runs_the_tests_of_its_function_and_only_then():
    """Catches a call of an always-inlined function (no gcov line of its own: seed 4001 [18]) recorded as
    run by no test while its function's tests run it, and the fallback used where the line's own
    tests exist or where no test runs the function either."""
    tests = [f"{FAR}::test_step", f"{NEAR}::test_helper", f"{NEAR}::test_clip"]
    record = {"tests": tests, "cost": [1.0, 2.0, 3.0], "slow": [False] * 3, "shared": {}, "shared_of": [[]] * 3,
              "failed": [], "all_tests": {t: {"seconds": s, "shared": []} for t, s in zip(tests, [1.0, 2.0, 3.0])},
              "lines": {"kernels/src/k.c": {"5": [1], "9": [0, 2], "11": [2], "12": [2]}}, "outside": {}}
    call = mm.select(record, "kernels/src/k.c", 10, 10, 100.0, enclosing=mm.c_function_lines(C_TEXT, 10))
    assert call["tests"] == [f"{FAR}::test_step", f"{NEAR}::test_clip"] and call["kind"] == "enclosing"
    assert call["covering"] == 0
    own = mm.select(record, "kernels/src/k.c", 12, 12, 100.0, enclosing=mm.c_function_lines(C_TEXT, 12))
    assert own["tests"] == [f"{NEAR}::test_clip"] and own["kind"] == "coverage"
    idle = {**record, "lines": {"kernels/src/k.c": {"5": [1]}}}
    assert mm.select(idle, "kernels/src/k.c", 10, 10, 100.0, enclosing=mm.c_function_lines(C_TEXT, 10))["kind"] == \
        "none"
