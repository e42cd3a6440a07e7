"""parcosim/checks.py on its own: each argparse type at its boundary and past it, refused by
name and value word for word; the suggestion for a misspelled name; the outermost folder a
command will make; an output refused before any work; and the folders a refused command made
taken back only while they hold no file (issue 31: these ran only through a few whole
commands, never at their edges)."""
from __future__ import annotations

import argparse
import os

import pytest

from parcosim.checks import (CommandError, Parser, at_least, check_output, first_missing, non_negative,
                             remove_if_empty, suggestion)


@pytest.mark.parametrize("least", [0, 1, 2])
def test_at_least_takes_the_least_and_above_and_refuses_below_or_not_an_integer(least):
    """Catches the boundary off by one (or the comparison reversed), a float or text taken,
    and a message without the option and the text given."""
    check = at_least(least, "--n")
    assert check(str(least)) == least and check(str(least + 7)) == least + 7
    for text in (str(least - 1), "2.5", "x", ""):
        with pytest.raises(argparse.ArgumentTypeError) as refused:
            check(text)
        assert str(refused.value) == f"--n = {text} must be an integer >= {least}"


def test_non_negative_takes_zero_and_up_and_refuses_negative_and_non_finite():
    """Catches the boundary moved off 0 (1e-300 refused, or -1e-300 taken), NaN or infinity
    taken, and a message without the option and the text given."""
    check = non_negative("--u")
    assert [check(t) for t in ("0", "0.0", "1e-300", "0.2", "7")] == [0.0, 0.0, 1e-300, 0.2, 7.0]
    for text in ("-1e-300", "-0.1", "nan", "inf", "-inf", "x"):
        with pytest.raises(argparse.ArgumentTypeError) as refused:
            check(text)
        assert str(refused.value) == f"--u = {text} must be a finite number >= 0"


def test_the_suggestion_is_the_closest_name_or_none():
    """Catches a suggestion for a name like none of them, or not the closest."""
    names = ["bench_circle_TCMDx", "bench_circle_PDq", "pendulum_balance"]
    assert suggestion("bench_circle_PDx", names) == "; did you mean 'bench_circle_PDq'?"
    assert suggestion("pendulum_balanse", names) == "; did you mean 'pendulum_balance'?"
    assert suggestion("zzz", names) == "" and suggestion("bench", names) == ""     # 0.48 alike: under 0.6


def test_the_parser_refuses_in_one_line_naming_its_help():
    """Catches argparse's usage block and exit instead of one CommandError headed by the program."""
    parser = Parser(prog="parcosim run")
    parser.add_argument("--k", type=int)
    with pytest.raises(CommandError) as refused:
        parser.parse_args(["--k", "x"])
    assert refused.value.head == "parcosim run"
    assert str(refused.value) == "argument --k: invalid int value: 'x' (`parcosim run --help` lists the options)"
    assert CommandError("m").head == "parcosim: error"


def test_the_first_missing_folder_is_the_outermost_one_the_command_will_make(tmp_path):
    """Catches the innermost folder returned (a refusal would then leave the outer ones), an
    existing folder returned, and a dangling symbolic link taken as missing."""
    assert first_missing(tmp_path) is None
    assert first_missing(tmp_path / "a" / "b" / "c") == tmp_path / "a"
    (tmp_path / "a").mkdir()
    assert first_missing(tmp_path / "a" / "b" / "c") == tmp_path / "a" / "b"
    (tmp_path / "link").symlink_to(tmp_path / "nowhere")
    assert first_missing(tmp_path / "link") is None


def test_an_output_the_command_could_not_write_is_refused_and_nothing_is_made(tmp_path):
    """Catches a folder taken where a file goes, a file taken as a folder anywhere up the
    path, and a check that makes folders."""
    (tmp_path / "folder").mkdir()
    (tmp_path / "file").write_text("")
    check_output(tmp_path / "new" / "deeper", is_file=False)
    check_output(tmp_path / "new" / "x.fmu", is_file=True)
    check_output(tmp_path / "folder" / "x.fmu", is_file=True)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file", "folder"]
    refusals = [((tmp_path / "folder", True), f"{tmp_path / 'folder'} is a folder; give the file to write"),
                ((tmp_path / "file" / "out", False),
                 f"{tmp_path / 'file' / 'out'} is not writable: {tmp_path / 'file'} is a file, not a folder"),
                ((tmp_path / "file" / "a" / "x.ssp", True),
                 f"{tmp_path / 'file' / 'a' / 'x.ssp'} is not writable: {tmp_path / 'file'} is a file, not a folder")]
    for (path, is_file), message in refusals:
        with pytest.raises(CommandError) as refused:
            check_output(path, is_file)
        assert str(refused.value) == message


def test_a_refused_commands_folders_go_only_while_they_hold_no_file(tmp_path):
    """A folder holding a file anywhere keeps every folder (before the fix, the empty ones
    walked before the file went: ``made/a/b`` beside ``made/notes.txt``).  Catches a folder
    with a file removed, or its empty folders, empty sub-folders left behind, and an error
    on a folder that is not there."""
    made = tmp_path / "made"
    (made / "a" / "b").mkdir(parents=True)
    (made / "c").mkdir()
    remove_if_empty(made)
    assert not made.exists()
    (made / "a" / "b").mkdir(parents=True)
    (made / "a" / "b" / "result.csv").write_text("t\n")
    (made / "c").mkdir()
    remove_if_empty(made)
    assert (made / "a" / "b" / "result.csv").is_file()
    (made / "a" / "b" / "result.csv").unlink()
    (made / "notes.txt").write_text("")
    remove_if_empty(made)
    assert sorted(p.name for p in made.iterdir()) == ["a", "c", "notes.txt"] and (made / "a" / "b").is_dir()
    remove_if_empty(None)
    remove_if_empty(tmp_path / "never")
    file = tmp_path / "file"
    file.write_text("kept")
    remove_if_empty(file)
    assert file.read_text() == "kept" and os.path.isdir(made)


def test_an_output_in_a_folder_one_may_not_write_in_or_enter_is_refused(tmp_path, monkeypatch):
    """The nearest existing folder must be writable AND searchable (a file is made in it by
    name): either permission missing refuses the output naming that folder.  The permissions are
    faked (os.access), as the tests may run as root, who has both everywhere.  Catches one of
    the two bits not asked (a constant of the same kind as seed 3901's [71])."""
    path = tmp_path / "new" / "out"
    for denied in (os.W_OK, os.X_OK):
        monkeypatch.setattr(os, "access", lambda p, mode, denied=denied: not mode & denied)
        with pytest.raises(CommandError) as refused:
            check_output(path, is_file=False)
        assert str(refused.value) == f"{path} is not writable: no permission to write in folder {tmp_path}"
    monkeypatch.setattr(os, "access", lambda p, mode: True)
    check_output(path, is_file=False)
    assert list(tmp_path.iterdir()) == []
