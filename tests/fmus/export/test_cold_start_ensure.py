"""Which FMUs ``ensure_built`` builds (fmus/export/build.py): a missing one and one older than any
source it bundles are built, an up-to-date one is used as it is, a foreign file where ours
would go is refused, and a model that is not parcosim's is taken from its file or named as
missing (issue 31: each branch of the rule, with the build recorded, not run: fast)."""
from __future__ import annotations

import os
import zipfile

import pytest

from fmus.export import build
from fmus.export.mark import MARK


def _ours(path, model):
    with zipfile.ZipFile(path, "w") as z:
        z.writestr(MARK, f'{{"model": "{model}", "built_by": "parcosim"}}')
    return path


@pytest.fixture
def recorded(monkeypatch, tmp_path):
    """build_fmu recorded (the models asked for), writing our mark; the newest source's time."""
    asked = []

    def build_fmu(model, out_dir):
        asked.append(model)
        return _ours(out_dir / f"{model}.fmu", model)
    monkeypatch.setattr(build, "build_fmu", build_fmu)
    return asked, max(f.stat().st_mtime for f in build._sources())


def test_missing_and_stale_fmus_are_built_and_up_to_date_ones_kept(recorded, tmp_path):
    """Catches the age test inverted or dropped (every run rebuilding, or a stale FMU run with old
    code) and a missing FMU not built."""
    asked, newest = recorded
    stale = _ours(tmp_path / "Trajectory.fmu", "Trajectory")
    os.utime(stale, (newest - 10.0, newest - 10.0))
    fresh = _ours(tmp_path / "Derivator.fmu", "Derivator")
    os.utime(fresh, (newest + 10.0, newest + 10.0))
    paths = build.ensure_built(["Trajectory", "Derivator", "DCMotorDrive"], tmp_path)
    assert paths == {m: tmp_path / f"{m}.fmu" for m in ("Trajectory", "Derivator", "DCMotorDrive")}
    assert asked == ["Trajectory", "DCMotorDrive"]
    assert os.stat(fresh).st_mtime == newest + 10.0


def test_a_foreign_file_or_a_model_that_is_not_ours_is_not_built(recorded, tmp_path):
    """A foreign FMU named as ours is refused naming the way to run it; a model that is not
    parcosim's is its file when there, a FileNotFoundError naming it when not; nothing is built."""
    asked, _ = recorded
    with zipfile.ZipFile(tmp_path / "Derivator.fmu", "w") as z:
        z.writestr("modelDescription.xml", "<fmiModelDescription/>")
    with pytest.raises(build.ForeignFmuError, match=r"Derivator.fmu was not built by parcosim; to run it in place of "
                                                    r"Derivator, use --replace INSTANCE=PATH"):
        build.ensure_built(["Derivator"], tmp_path)
    (tmp_path / "Theirs.fmu").write_bytes(b"any")
    assert build.ensure_built(["Theirs"], tmp_path) == {"Theirs": tmp_path / "Theirs.fmu"}
    with pytest.raises(FileNotFoundError, match=r"no FMU .*Nobody.fmu and 'Nobody' is not a parcosim model"):
        build.ensure_built(["Nobody"], tmp_path)
    assert asked == []
