"""What ``fmus/export/build.py`` asks of a build, with the build recorded, not run (fast): the
files whose change makes ``ensure_built`` rebuild an FMU (every bundled module, the C wrapper
it installs and the build script itself), ``build_all`` listing each FMU built in the
registry's order without the foreign ones left alone, and ``build_fmu``'s arguments per model
(its slave module's script, the variable-step flag from the slave's sample period, the state
options, its feedthrough) and its refusal of an unknown model (issue 31: these ran only inside
full builds, where each is true of every model at once)."""
from __future__ import annotations

import importlib
import os
import zipfile
from pathlib import Path

import pytest

from fmus.export import build
from fmus.export.bundle import source_files
from fmus.export.mark import MARK
from fmus.export.wrapper import SOURCE as WRAPPER_SOURCE
from fmus.slave.registry import SLAVES


def _ours(path, model):
    with zipfile.ZipFile(path, "w") as z:
        z.writestr(MARK, f'{{"model": "{model}", "built_by": "parcosim"}}')
    return path


def test_the_sources_are_the_bundled_modules_the_wrapper_and_the_build_script():
    """Catches the wrapper's C source or build.py left out (an FMU built before they changed
    would be run with the old wrapper or the old options) and a bundled module left out."""
    sources = [Path(p).resolve() for p in build._sources()]
    assert WRAPPER_SOURCE.resolve() in sources
    assert Path(build.__file__).resolve() in sources
    assert set(sources) >= {Path(p).resolve() for _, p in source_files()}
    assert all(p.is_file() for p in sources)


@pytest.mark.parametrize("newer", ["wrapper", "script"])
def test_an_fmu_older_than_the_wrapper_or_the_build_script_alone_is_rebuilt(newer, tmp_path, monkeypatch):
    """The FMU is newer than every bundled module; only the wrapper's source (or build.py) is
    newer than it.  Catches either left out of the rule."""
    modules = max(Path(p).stat().st_mtime for _, p in source_files())
    stand_in = tmp_path / "stand_in"
    stand_in.write_text("x")
    os.utime(stand_in, (modules + 20.0, modules + 20.0))
    old = tmp_path / "old"
    old.write_text("x")
    os.utime(old, (modules - 20.0, modules - 20.0))
    monkeypatch.setattr(build, "WRAPPER_SOURCE", stand_in if newer == "wrapper" else old)
    monkeypatch.setattr(build, "__file__", str(stand_in if newer == "script" else old))
    asked = []
    monkeypatch.setattr(build, "build_fmu", lambda model, out: asked.append(model) or _ours(out / f"{model}.fmu", model))
    fmu = _ours(tmp_path / "Trajectory.fmu", "Trajectory")
    os.utime(fmu, (modules + 10.0, modules + 10.0))
    assert build.ensure_built(["Trajectory"], tmp_path) == {"Trajectory": fmu}
    assert asked == ["Trajectory"]
    # The stand-in older than the FMU too: nothing is rebuilt.
    os.utime(stand_in, (modules, modules))
    asked.clear()
    build.ensure_built(["Trajectory"], tmp_path)
    assert asked == []


def test_build_all_lists_the_fmus_built_in_the_registry_order_and_not_the_foreign_ones(tmp_path, monkeypatch):
    """build_fmu's None is a foreign file left alone.  Catches the filter inverted (only the
    Nones listed) or dropped, and a model skipped."""
    models = list(SLAVES)
    foreign = models[1]
    asked = []

    def build_fmu(model, out_dir):
        asked.append((model, out_dir))
        return None if model == foreign else out_dir / f"{model}.fmu"
    monkeypatch.setattr(build, "build_fmu", build_fmu)
    assert build.build_all(tmp_path) == [tmp_path / f"{m}.fmu" for m in models if m != foreign]
    assert asked == [(m, tmp_path) for m in models]


def test_each_model_is_built_from_its_slave_script_with_its_own_step_flag_and_feedthrough(tmp_path, monkeypatch):
    """Catches another script or target, the variable-step flag not "false" exactly for a
    slave with a sample period (docs: a sampled component cannot take any step), the state
    options or the feedthrough not passed."""
    calls = []
    monkeypatch.setattr(build, "build_bundled_fmu", lambda *args, **kwargs: calls.append((args, kwargs)) or args[2])
    for model, module in SLAVES.items():
        calls.clear()
        assert build.build_fmu(model, tmp_path) == tmp_path / f"{model}.fmu"
        ((args, kwargs),) = calls
        assert args == (build.ROOT / "fmus" / "slaves" / f"{module}.py", model, tmp_path / f"{model}.fmu")
        slave = getattr(importlib.import_module(f"fmus.slaves.{module}"), model)
        sampled = getattr(slave, "has_sample_period", False)
        assert kwargs == {"feedthrough": getattr(slave, "feedthrough", {}),
                          "canHandleVariableCommunicationStepSize": "false" if sampled else "true",
                          "canGetAndSetFMUstate": "true", "canSerializeFMUstate": "true"}, model
    assert any(getattr(getattr(importlib.import_module(f"fmus.slaves.{m}"), n), "has_sample_period", False)
               for n, m in SLAVES.items())   # both flags are exercised


def test_an_unknown_model_is_refused_naming_it_and_the_valid_ones(tmp_path):
    with pytest.raises(ValueError, match=rf"^unknown FMU 'Nobody'; valid: {', '.join(SLAVES)}$"):
        build.build_fmu("Nobody", tmp_path)
    assert list(tmp_path.iterdir()) == []
