"""The C mutation tool's operators (benchmarks/mutation_c.py), on small C snippets: each yields
the mutants it should and nothing in comments, strings, preprocessor lines or field lists.
Nothing is built here."""
import pytest

from benchmarks.mutation_c import Mutant, mutants_of


def changes(text, operator=None):
    """``(line, before, after)`` of every mutant of ``text`` (of one operator)."""
    return {(m.line, m.before, m.after) for m in mutants_of("x.c", text) if operator in (None, m.operator)}


def test_arith_swaps_binary_operators_only():
    found = changes("y = a + b * c - d / e;\np->q = -x; ++i; i--; double *p = &v;", "arith")
    assert found == {(1, "+", "-"), (1, "*", "/"), (1, "-", "+"), (1, "/", "*")}


def test_compare_swaps_strictness_and_equality_not_shifts_or_arrows():
    found = changes("if (a < b && c >= d && e == f && g != h) k = p->q << 1;", "compare")
    assert found == {(1, "<", "<="), (1, ">=", ">"), (1, "==", "!="), (1, "!=", "==")}


def test_constant_doubles_numbers_and_flips_zero_and_one():
    found = changes("y = x[0] + 2.5 * z[1] + 3 + 0.0 + 1e-9 + c01;", "constant")
    assert found == {(1, "0", "1"), (1, "2.5", "5.0"), (1, "1", "0"), (1, "3", "6"), (1, "0.0", "1.0"),
                     (1, "1e-9", "2e-09")}


def test_drop_removes_a_simple_right_operand_but_not_a_product():
    found = changes("y = a + b - c * d + p->q;", "drop")
    assert found == {(1, " + b", ""), (1, " + p->q", "")}


def test_swap_exchanges_adjacent_arguments_and_indices():
    found = changes("y = f(a, b, c) + m[i][j] + g(a, a);", "swap")
    assert found == {(1, "a, b, c", "b, a, c"), (1, "a, b, c", "a, c, b"), (1, "[i][j]", "[j][i]")}


def test_comments_strings_preprocessor_and_field_lists_yield_nothing():
    text = ("/* a + b < c\n   f(x, y) * 2 */\n// z = a - 1;\n#define N (2 * 3)\n#include <math.h>\n"
            "    PC_FIELD(pc_x, a), PC_FIELD(pc_x, b),\nconst char *s = \"a + b < 2\";")
    assert {line for line, _, _ in changes(text)} == set()


def test_a_mutant_applies_at_its_column_and_refuses_a_stale_position():
    text = "int f(void)\n{\n    return a + b;\n}"
    mutant = next(m for m in mutants_of("x.c", text) if m.operator == "arith")
    assert mutant.apply(text).split("\n")[2] == "    return a - b;"
    moved = Mutant("x.c", 3, mutant.column + 1, "arith", "+", "-")
    with pytest.raises(ValueError, match="x.c:3"):
        moved.apply(text)
