"""benchmarks/mutation.py's retest finds a recorded mutant again in an edited file
(cosmic-ray names a mutant by operator and occurrence, which an edit above it shifts)."""
from __future__ import annotations

import difflib

import pytest

pytest.importorskip("cosmic_ray")

from benchmarks import mutation  # noqa: E402
from tests import layout_rules  # noqa: E402

pytestmark = [pytest.mark.tools]

OPERATOR = "core/ReplaceBinaryOperator_Add_Sub"
SOURCE = """def f(a, b):
    x = a + b
    y = x * 2
    x = a + b
    return x + y


def g(a, b):
    return a + b
"""


def _mutants(path):
    """(MutationSpec, diff) of every mutant of OPERATOR in ``path``, as cosmic-ray records them."""
    import cosmic_ray.plugins
    from cosmic_ray.ast import ast_nodes, get_ast_from_path
    from cosmic_ray.ast.ast_query import ASTQuery
    from cosmic_ray.mutating import mutate_code
    from cosmic_ray.work_item import MutationSpec

    operator = cosmic_ray.plugins.get_operator(OPERATOR)()
    code = path.read_text()
    positions = [(node, start, end) for node in ast_nodes(get_ast_from_path(path))
                 for start, end in operator.mutation_positions(node)]
    out = []
    for occurrence, (node, start, end) in enumerate(positions):
        mutated = mutate_code(code, operator, occurrence)
        diff = "\n".join(difflib.unified_diff(code.split("\n"), mutated.split("\n"), "a/m.py", "b/m.py",
                                              lineterm=""))
        out.append((MutationSpec(path.name, OPERATOR, occurrence, start, end,
                                 definition_name=ASTQuery(node).get_definition_name()), diff))
    return out


@pytest.fixture
def module(tmp_path, monkeypatch):
    monkeypatch.setattr(mutation, "ROOT", tmp_path)
    path = tmp_path / "m.py"
    path.write_text(SOURCE)
    return path


def test_an_unchanged_file_gives_back_every_mutant(module):
    """Catches a resumed campaign that cannot relocate mutants of a file that did not change (they would be
    dropped)."""
    recorded = _mutants(module)
    assert len(recorded) == 4
    for spec, diff in recorded:
        assert mutation._relocated(spec, diff) == spec


def test_an_edit_above_shifts_the_mutants_and_the_retest_finds_each_again(module):
    """Four lines and one addition inserted above: each mutant, the repeated line
    ``x = a + b`` of f included (told apart by its context), is the occurrence one
    further, four lines lower, and makes the recorded change."""
    recorded = _mutants(module)
    module.write_text("def h(c):\n    return c + 1\n\n\n" + SOURCE)
    now = {spec.occurrence: diff for spec, diff in _mutants(module)}
    for spec, diff in recorded:
        found = mutation._relocated(spec, diff)
        assert found.occurrence == spec.occurrence + 1 and found.start_pos[0] == spec.start_pos[0] + 4
        assert mutation._hunk(now[found.occurrence]) == mutation._hunk(diff)


def test_a_changed_line_is_not_re_run(module):
    """Catches a resumed campaign re-running a stored mutant whose line changed since (its outcome no
    longer applies), or dropping one whose line did not."""
    recorded = _mutants(module)
    module.write_text(SOURCE.replace("    return a + b", "    return a + 2 * b"))
    assert mutation._relocated(*recorded[3]) is None                    # g's line changed
    assert mutation._relocated(*recorded[0]) == recorded[0][0]          # f's untouched


def test_every_target_names_an_existing_test():
    """A stale target (a renamed module or test) makes pytest error out, and cosmic-ray would
    count every mutant of that source as killed: each target must exist."""
    import ast
    from pathlib import Path

    root = Path(mutation.__file__).resolve().parents[1]
    for source, targets in mutation.TARGETS.items():
        assert (root / source).is_file(), source
        for target in targets:
            module, _, test = target.partition("::")
            path = root / layout_rules.path_of(module)
            assert path.is_file(), (source, target)
            if test:
                names = {n.name for n in ast.walk(ast.parse(path.read_text())) if isinstance(n, ast.FunctionDef)}
                assert test in names, (source, target)
        assert mutation._test_command(source).count("tests/") == len(targets)
