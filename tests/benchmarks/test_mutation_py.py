"""benchmarks/mutation_py.py's operators on snippets (nothing is run): each makes the change
it names, every mutant applies to its file and compiles, and docstrings, annotations and
f-strings are left alone; the draw is seeded; the importers are found."""
from __future__ import annotations

import ast

from benchmarks import mutation_py as mp

SNIPPET = '''"""Module docstring: a + b."""
from __future__ import annotations


def torque(kt: float, i: float, omega: float, b=0.1) -> float:
    """kt i - b omega."""
    scale = 2.0
    offset = 0.5
    rows = make(3)
    label = f"{kt + i}"
    x = kt * i - b * omega + offset
    if x < 0.0 and not rows:
        x = -x
    rows[0][1] = rows[1, 2]
    total = combine(kt, i, limit=scale)
    return x / scale + total
'''


def _mutants(operator=None):
    found = mp.mutants_of_python("snippet.py", SNIPPET)
    return [m for m in found if operator is None or m.operator == operator]


def _changes(operator):
    return {(m.before, m.after) for m in _mutants(operator)}


def test_every_mutant_applies_and_compiles_and_changes_the_tree():
    """Catches an operator that yields a syntax error or an equivalent (unchanged) tree, or an operator
    never drawn."""
    found = _mutants()
    assert {m.operator for m in found} == set(mp.PY_OPERATORS) | {"replace_var"}
    original = ast.dump(ast.parse(SNIPPET))
    for m in found:
        mutated = m.apply(SNIPPET)
        compile(mutated, "snippet.py", "exec")
        assert ast.dump(ast.parse(mutated)) != original, m


def test_docstrings_annotations_and_f_strings_are_not_mutated():
    """Catches mutants drawn in docstrings, annotations or f-strings, which no test can kill."""
    for m in _mutants():
        assert "docstring" not in m.before and "kt i - b omega" not in m.before
        assert m.line not in (1, 5, 6, 10) or "float" not in m.before and "{" not in m.before, m


def test_a_process_argument_is_never_mutated():
    """Catches a mutant that would pin, signal or wait on another process of the machine (the campaigns
    run as root: ``os.sched_setaffinity(0, ...)`` -> ``(1, ...)`` pins PID 1), while the rest of the call
    and the same constants elsewhere still are."""
    text = ("import os\n\n\ndef f(pid, other):\n    os.sched_setaffinity(0, {1})\n    os.kill(pid, 9)\n"
            "    return 0 + other\n")
    found = mp.mutants_of_python("p.py", text)
    on_line = {line: [(m.operator, m.before, m.after) for m in found if m.line == line] for line in (5, 6, 7)}
    assert not any(before in ("0", "pid") for _, before, _ in on_line[5] + on_line[6]), on_line
    assert ("constant", "1", "(2)") in on_line[5] and ("constant", "9", "(18)") in on_line[6]
    assert ("constant", "0", "(1)") in on_line[7]


def test_the_new_operators_make_their_changes():
    """Catches drop_term, swap_args, drop_arg, swap_index or constant producing another change than the one
    each promises."""
    assert ("kt * i - b * omega + offset", "(kt * i - b * omega)") in _changes("drop_term")
    assert ("kt * i", "(kt)") in _changes("drop_term")
    assert ("combine(kt, i, limit=scale)", "(combine(i, kt, limit=scale))") in _changes("swap_args")
    dropped = _changes("drop_arg")
    assert ("combine(kt, i, limit=scale)", "(combine(kt, limit=scale))") in dropped
    assert ("combine(kt, i, limit=scale)", "(combine(kt, i))") in dropped
    assert ("rows[0][1]", "(rows[1][0])") in _changes("swap_index")
    assert ("rows[1, 2]", "(rows[2, 1])") in _changes("swap_index")
    assert ("0.5", "(1.0)") in _changes("constant") and ("0.0", "(1.0)") in _changes("constant")


def test_replace_var_takes_a_local_of_the_same_kind_defined_before():
    """Catches replace_var swapping in a name of another kind or one not yet defined (mutants that fail on
    a NameError or a type error, not on a test)."""
    changes = _changes("replace_var")
    assert ("scale", "(offset)") in changes            # both assigned numbers; offset defined before use
    assert ("kt", "(i)") in changes                    # both annotated float
    assert not any(after == "(rows)" for before, after in changes if before in ("scale", "kt", "i", "offset"))
    assert not any(before == "omega" and after == "(b)" for before, after in changes)   # annotated vs not


def test_classic_operators():
    """Catches a mutation operator (compare, boolean, arith) that does not make its classic change."""
    assert ("x < 0.0", "(x <= 0.0)") in _changes("compare")
    assert ("x < 0.0 and not rows", "(x < 0.0 or not rows)") in _changes("boolean")
    assert ("not rows", "(rows)") in _changes("boolean")
    assert ("x / scale", "(x * scale)") in _changes("arith")


def test_the_draw_is_seeded_and_distinct(monkeypatch):
    """Catches a draw that depends on anything but the seed, draws a mutant twice, or ignores the files'
    line counts as weights."""
    monkeypatch.setattr(mp, "line_count", lambda name: {"a.py": 900, "b.py": 100}[name])
    pool = {"a.py": mp.mutants_of_python("a.py", SNIPPET), "b.py": mp.mutants_of_python("b.py", SNIPPET)}
    first, again = mp.draw(pool, 7, 40), mp.draw(pool, 7, 40)
    assert first == again and len(set(map(repr, first))) == 40
    assert sum(name == "a.py" for name, _ in first) > 25          # weighted by lines (expected 36 of 40)


def test_the_importers_are_every_test_file_that_imports_a_module_near_or_by_a_string_name():
    """Catches an importer list missing the tests that import a module only by a string name, listing
    tests that are not run, cut to a few files, or leaving the slow files out (their tests may be the only
    ones that execute a line)."""
    mapping = mp.importers()
    assert "tests/fmus/export/test_oracles_export.py" in mapping["fmus.ssp.export"]
    assert mapping["fmus.slaves.parcosim_derivator"]          # loaded by importlib from a "fmus.slaves." name
    assert all(not t.startswith(mp.NOT_RUN) for tests in mapping.values() for t in tests)
    assert max(len(tests) for tests in mapping.values()) > 6
    assert "tests/fmus/hostile/test_hostile.py" in mapping["fmus.hostile.cases"]      # a slow file


def test_a_bundled_copy_counts_as_its_product_file():
    """Catches coverage of the copy an FMU bundles (or a test file) not mapped back to the product file."""
    from benchmarks import mutation_map as mm
    products = {"plant/drive.py", "fmus/slaves/parcosim_plant.py"}
    assert mm._product_file("/tmp/fmpy_x/resources/parcosim_b1/plant/drive.py", products) == "plant/drive.py"
    assert mm._product_file("/tmp/copy/fmus/slaves/parcosim_plant.py", products) == "fmus/slaves/parcosim_plant.py"
    assert mm._product_file("/tmp/copy/tests/test_drive.py", products) is None


def test_the_report_counts_per_area_and_lists_survivors():
    """Catches a report that counts a mutant in the wrong area, miscounts the score, or leaves a survivor
    out of the list."""
    from benchmarks.mutation_report import area, table
    assert area("kernels/src/drive.c") == "kernels C" and area("controller/law.py") == "law"
    assert area("fmus/ssp.py") == "fmus export/SSP/state/refusals" and area("fmus/slaves/parcosim_derivator.py") == "fmus other"
    # the same modules after the layout of issue 29 (a fresh draw of today's tree)
    assert area("fmus/ssp/export.py") == area("fmus/slave/state_format.py") == "fmus export/SSP/state/refusals"
    assert area("fmus/slave/sampling.py") == area("fmus/cosim/stepper.py") == "fmus other"
    header = {"seed": 1, "commit": "abc", "sample": 3, "lines": {"plant/a.py": 10, "controller/law.py": 5},
              "drawn": ["plant/a.py", "plant/a.py", "controller/law.py"]}
    base = {"column": 0, "before": "a", "after": "b", "operator": "arith", "seconds": 1.0}
    done = {0: dict(base, index=0, file="plant/a.py", line=1, outcome="killed"),
            1: dict(base, index=1, file="plant/a.py", line=2, outcome="survived", note="no test executes the line"),
            2: dict(base, index=2, file="controller/law.py", line=3, outcome="killed")}
    text = table(header, done)
    assert "| plant | 10 | 2 | 2 | 1 | 1 | 0 | 0 | 50.0 % |" in text
    assert "| law | 5 | 1 | 1 | 1 | 0 | 0 | 0 | 100.0 % |" in text
    assert "| **total** | 15 | 3 | 3 | 2 | 1 | 0 | 0 | 66.7 % |" in text
    assert "- [1] plant/a.py:2:0 (arith) 'a' -> 'b' [no test executes the line]" in text


def test_a_resume_from_a_tree_whose_draw_differs_is_refused(monkeypatch, tmp_path):
    """Catches a resume that reads the pool from a tree where files moved since the draw (the
    check of ``header["drawn"]`` dropped): it would run other mutants under the old indices."""
    import json
    monkeypatch.setattr(mp, "line_count", lambda name: 100)
    pool = {"a.py": mp.mutants_of_python("a.py", SNIPPET), "b.py": mp.mutants_of_python("b.py", SNIPPET)}
    monkeypatch.setattr(mp, "pool_by_file", lambda: pool)
    drawn = [name for name, _ in mp.draw(pool, 7, 5)]
    results = tmp_path / "m.jsonl"
    moved = ["c.py" if name == "a.py" else name for name in drawn]
    results.write_text(json.dumps({"header": {"seed": 7, "sample": 5, "commit": "0" * 40, "drawn": moved}}) + "\n")
    from benchmarks import mutation_run
    try:
        mutation_run.campaign(7, 5, 1, results)
    except ValueError as refused:
        assert "drawn from the product files of commit 0000000000" in str(refused)
    else:
        raise AssertionError("a draw that differs from the recorded one was resumed")
