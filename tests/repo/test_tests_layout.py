"""The tests sit in folders by the product layer they test (tests/layout_rules.py, issue 29 item 5).

Catches: a new test file left in tests/ or put in a folder its rule does not give, a test file
whose name no rule matches, a folder of tests that is not a package (two ``test_x.py`` of the
same name in two folders would then clash), a rule that points at no layer of docs/layout.md,
and a ``--move`` that loses or misplaces a file.
"""
from __future__ import annotations

import subprocess

import pytest

from tests import layout_rules
from tests.support.paths import ROOT, TESTS


def test_every_test_file_is_in_the_folder_its_rule_gives():
    wrong = [f"{path.relative_to(ROOT)} -> {'no rule' if wanted is None else wanted.relative_to(ROOT)}"
             for path, wanted in layout_rules.misplaced()]
    assert not wrong, "run `python tests/layout_rules.py --move` (or add a rule): " + "; ".join(wrong)


def test_the_rules_see_the_test_files():
    """An empty or mis-rooted listing would pass the check above."""
    files = layout_rules.test_files()
    assert len(files) > 100 and all(p.name.startswith("test_") for p in files)
    assert not list(TESTS.glob("test_*.py"))


def test_every_folder_of_tests_is_a_package():
    """Catches a tests folder without __init__.py, whose test files then collide by basename under pytest's
    rootdir import mode."""
    for folder in {p.parent for p in layout_rules.test_files()}:
        for here in (folder, *folder.parents[:len(folder.relative_to(TESTS).parts)]):
            assert (here / "__init__.py").exists(), f"{here.relative_to(ROOT)} has no __init__.py"


def test_every_rule_names_a_product_folder_or_one_of_the_others():
    """A rule's folder is a product folder (kernels, fmus/cosim ...), or cli, benchmarks or repo."""
    for _, folder in layout_rules.RULES:
        assert folder in ("cli", "benchmarks", "repo") or (ROOT / folder / "__init__.py").exists(), folder


@pytest.mark.parametrize("name, folder", [("test_kernels_new.py", "kernels"), ("test_fmu_state_x.py", "fmus/slave"),
                                          ("test_fmu_new.py", "fmus/slaves"), ("test_wheeled_fmu.py", "fmus/slaves"),
                                          ("test_wheeled.py", "plant"), ("test_native_x.py", "fmus/native")])
def test_the_first_matching_rule_wins(name, folder):
    assert layout_rules.folder_of(name) == folder


def test_a_name_no_rule_matches_is_refused_by_name():
    with pytest.raises(LookupError, match="test_zzz_unknown.py"):
        layout_rules.folder_of("test_zzz_unknown.py")


def test_move_puts_a_stray_file_in_its_folder_and_makes_the_folder_a_package(tmp_path):
    """In a scratch git repository: a file in tests/ and one in the wrong folder are moved, the
    right one stays, and a new folder gets its __init__.py."""
    tests = tmp_path / "tests"
    (tests / "plant").mkdir(parents=True)
    (tests / "__init__.py").write_text("")
    (tests / "plant" / "__init__.py").write_text("")
    (tests / "test_kernels_stray.py").write_text("x = 1\n")
    (tests / "plant" / "test_motor_lost.py").write_text("y = 2\n")
    (tests / "plant" / "test_serial_home.py").write_text("z = 3\n")
    subprocess.run(["git", "init", "-q"], cwd=tmp_path, check=True)
    subprocess.run(["git", "add", "."], cwd=tmp_path, check=True)
    moved = layout_rules.move(tests)
    assert sorted(str(new) for _, new in moved) == ["tests/kernels/test_kernels_stray.py", "tests/motor/test_motor_lost.py"]
    assert (tests / "kernels" / "test_kernels_stray.py").read_text() == "x = 1\n"
    assert (tests / "kernels" / "__init__.py").exists() and (tests / "motor" / "__init__.py").exists()
    assert (tests / "plant" / "test_serial_home.py").exists() and not (tests / "test_kernels_stray.py").exists()
    assert layout_rules.misplaced(tests) == []


def test_move_refuses_and_moves_nothing_when_a_file_has_no_rule(tmp_path):
    tests = tmp_path / "tests"
    tests.mkdir()
    (tests / "test_kernels_stray.py").write_text("")
    (tests / "test_zzz_unknown.py").write_text("")
    with pytest.raises(LookupError, match="tests/test_zzz_unknown.py"):
        layout_rules.move(tests)
    assert (tests / "test_kernels_stray.py").exists()
