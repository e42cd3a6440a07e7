"""``parcosim run --mode fmu --native --fmi-version N``: 2 runs the native FMUs, 3 is refused in
one line with exit 2 before anything is built (the master's FMU back end is FMI 2.0:
``parcosim.cli.FMI3_RUN_REFUSED``, docs/native.md "FMI 3.0")."""
from __future__ import annotations

import pytest

import fmus.native.run as native_run
from parcosim.cli import EXIT_INTERRUPTED, main

SCENE = "bench_circle_TCMDx"


@pytest.fixture
def reached(monkeypatch):
    """Records whether the run got to building its native FMUs, and stops it there (as
    Ctrl-C would: exit 130), so no FMU is built."""
    calls = []

    def with_native_fmus(scene, out_dir):
        calls.append(scene.name)
        raise KeyboardInterrupt

    monkeypatch.setattr(native_run, "with_native_fmus", with_native_fmus)
    return calls


def test_fmi3_through_the_master_is_refused_in_one_line_before_any_build(tmp_path, reached, capsys):
    """Catches ``--fmi-version 3`` accepted and ignored (an FMI 2.0 run said to be FMI 3.0),
    refused only after the native FMUs were built or deep in the master, or refused by
    argparse without saying why."""
    out = tmp_path / "out"
    assert main(["run", SCENE, "--mode", "fmu", "--native", "--fmi-version", "3", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert "--fmi-version 3" in err[0] and "FMI 2.0" in err[0] and "export-fmu" in err[0], err
    assert reached == [] and not out.exists()


def test_fmi2_named_explicitly_runs_the_native_fmus(tmp_path, reached, capsys):
    """Catches the new option refusing or bypassing its default: ``--fmi-version 2`` must
    reach the native run as a run without the option does."""
    for extra in ([], ["--fmi-version", "2"]):
        assert main(["run", SCENE, "--mode", "fmu", "--native", "--out", str(tmp_path / "o"), *extra]) \
            == EXIT_INTERRUPTED
    assert reached == [SCENE, SCENE]


def test_fmi3_without_native_names_native(tmp_path, reached, capsys):
    """Catches the FMI 3.0 refusal hiding the older rule: without ``--native`` the option is
    for the native FMUs, whatever the version."""
    assert main(["run", SCENE, "--fmi-version", "3", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "it needs --native" in err[0], err
    assert reached == []
