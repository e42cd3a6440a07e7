"""``python -m fmus.native.build [OUT]``, the native FMUs' own command line, run as ``__main__``
with the models cut down to the Trajectory (the smallest, to keep it fast): it builds into OUT
when given, prints each FMU's path, and the FMU there is a native one of that model (issue 31:
seed 3501's survivor [28], OUT ignored when ``len(sys.argv) > 1`` read as ``> 2``)."""
from __future__ import annotations

import json
import runpy
import sys
import warnings
import zipfile

import pytest

from fmus.native import models
from fmus.native.build import platform_folder
from fmus.slave.identity import IDENTITY_FILE


def test_the_command_line_builds_every_native_model_into_out_and_prints_its_path(monkeypatch, tmp_path, capsys):
    """Catches OUT ignored (the FMUs written to the default folder in the repository), a path
    not printed, and a model left out or built as another."""
    monkeypatch.setattr(models, "NATIVE", {"Trajectory": models.NATIVE["Trajectory"]})
    out = tmp_path / "out"
    monkeypatch.setattr(sys, "argv", ["build", str(out)])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)     # runpy: the module is already imported
        runpy.run_module("fmus.native.build", run_name="__main__")
    target = out / "Trajectory.fmu"
    assert capsys.readouterr().out.splitlines() == [str(target)]
    assert sorted(p.name for p in out.iterdir()) == ["Trajectory.fmu"]
    with zipfile.ZipFile(target) as z:
        identity = json.loads(z.read(f"resources/{IDENTITY_FILE}"))
        assert f"binaries/{platform_folder(2)}/Trajectory.so" in z.namelist()
    assert identity["model"] == "Trajectory" and identity["native"] is True and identity["fmi_version"] == 2


def test_every_model_named_native_has_a_model_the_registry_knows():
    """Catches a native model without a slave (``build_native_all`` would stop at it)."""
    from fmus.slave.registry import SLAVES

    assert set(models.NATIVE) <= set(SLAVES) and "Trajectory" in models.NATIVE
    from fmus.native.build import build_native_fmu

    with pytest.raises(ValueError, match="no native FMU of 'Nothing'; native: "):
        build_native_fmu("Nothing")


@pytest.mark.parametrize("content", [b"not an fmu", None])
def test_a_file_not_built_by_parcosim_at_the_target_is_refused_naming_it_and_left_alone(tmp_path, content):
    """Catches a native build that overwrites a file parcosim did not make (a supplier's FMU,
    any file) at its target, or refuses without naming the path."""
    import shutil
    from fmus.native.build import NativeBuildError, build_native_fmu

    target = tmp_path / "Derivator.fmu"
    if content is None:                       # a zip that is no parcosim FMU
        shutil.make_archive(str(tmp_path / "Derivator"), "zip", root_dir=tmp_path, base_dir=".")
        (tmp_path / "Derivator.zip").rename(target)
    else:
        target.write_bytes(content)
    before = target.read_bytes()
    with pytest.raises(NativeBuildError) as refused:
        build_native_fmu("Derivator", tmp_path)
    assert str(refused.value) == f"{target} was not built by parcosim: left alone"
    assert target.read_bytes() == before and [p.name for p in tmp_path.iterdir()] == ["Derivator.fmu"]
