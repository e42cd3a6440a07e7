"""fmus/native/run.py's cache of native FMUs (:func:`native_fmu_for`): one file per model,
parameters and sources, built once and taken again while all three are the same (the build is
recorded, not run: what is checked is which file is asked for and when it is built)."""
from __future__ import annotations

from fmus.native import run


def _recording_build(monkeypatch, digests):
    """Record each build (model, folder, start values, file name) and write its file; the
    sources' digest is the next of ``digests`` at each call of ``source_digest``."""
    built, asked = [], iter(digests)

    def build(model, out_dir, start_values, file_name):
        built.append((model, start_values, file_name))
        path = out_dir / f"{file_name}.fmu"
        path.write_text("fmu")
        return path

    monkeypatch.setattr(run, "build_native_fmu", build)
    monkeypatch.setattr(run, "source_digest", lambda: next(asked))
    return built


def test_a_native_fmu_is_built_once_per_model_parameters_and_sources(monkeypatch, tmp_path):
    """Catches a cached FMU taken after the sources changed (a name without their digest), one
    built again for the same model, parameters and sources, a given digest not used, or the
    parameters not passed on as the start values."""
    built = _recording_build(monkeypatch, ["sources-1", "sources-1", "sources-2"])
    first = run.native_fmu_for("Derivator", {"h": 1e-3}, tmp_path)
    assert first.parent == tmp_path and first.name.startswith("Derivator-") and first.exists()
    assert run.native_fmu_for("Derivator", {"h": 1e-3}, tmp_path) == first          # same sources: cached
    changed = run.native_fmu_for("Derivator", {"h": 1e-3}, tmp_path)                # the sources changed
    assert changed != first
    assert [b[1] for b in built] == [{"h": 1e-3}, {"h": 1e-3}]
    assert [f"{b[2]}.fmu" for b in built] == [first.name, changed.name]
    # a digest given is the sources' (source_digest is not asked again: its list is used up)
    assert run.native_fmu_for("Derivator", {"h": 1e-3}, tmp_path, digest="sources-1") == first
    assert run.native_fmu_for("Derivator", {"h": 1e-3}, tmp_path, digest="sources-2") == changed
    other = run.native_fmu_for("Derivator", {"h": 2e-3}, tmp_path, digest="sources-2")
    assert other not in (first, changed) and built[-1][1] == {"h": 2e-3} and len(built) == 3


def test_a_system_runs_its_native_models_as_their_fmus_and_keeps_the_others(monkeypatch, tmp_path):
    """Each component of a natively built model becomes its own native FMU file (absolute path,
    its own parameters as start values); the others, and the connections, stay as they are; a
    scene says which ran natively ("none" when none).  Catches a component of another model
    replaced, two instances of one model given one FMU, or the description naming others."""
    from dataclasses import dataclass

    from fmus.cosim.system import Component, Connection, System

    built = _recording_build(monkeypatch, ["s"] * 4)
    system = System((Component("d1", "Derivator", {"fc_vel": 40.0}), Component("p", "SpecPlant"),
                     Component("d2", "Derivator", {"fc_vel": 20.0})),
                    (Connection("d1.y", "d2.u"),), ("d2.y",), stop_time=0.1, step=1e-3)
    native = run.native_system(system, tmp_path)
    d1, p, d2 = native.components
    assert p == system.components[1] and native.connections == system.connections
    assert d1.model == str((tmp_path / f"{built[0][2]}.fmu").resolve()) and d1.parameters == {"fc_vel": 40.0}
    assert d2.model != d1.model and [b[1] for b in built] == [{"fc_vel": 40.0}, {"fc_vel": 20.0}]

    @dataclass(frozen=True)
    class Scene:
        system: System
        description: str

    assert run.with_native_fmus(Scene(system, "a scene"), tmp_path).description == "a scene; native FMUs: d1, d2"
    plain = System((Component("p", "SpecPlant"),), (), (), 0.1)
    assert run.with_native_fmus(Scene(plain, "b"), tmp_path).description == "b; native FMUs: none"


def test_components_without_a_native_fmu_are_refused_in_one_line_and_fmu_files_go_as_they_are(tmp_path):
    import pytest

    from fmus.cosim.system import Component, System
    from fmus.native.models import NATIVE
    from tests.fmus.export.test_oracles_export import fake_fmu

    fmu = fake_fmu(tmp_path / "Other.fmu", "Other")
    system = System((Component("s1", "SpecPlant"), Component("traj", "Trajectory"), Component("ext", str(fmu)),
                     Component("s2", "SpecPlant")), (), (), 0.1)
    with pytest.raises(ValueError) as refused:
        run.refuse_without_native(system, "scene x: export-ssp --native")
    assert str(refused.value) == (f"scene x: export-ssp --native: no native FMU of s1 (SpecPlant), s2 (SpecPlant) "
                                  f"(native: {', '.join(NATIVE)}); export it without --native")
    run.refuse_without_native(System(system.components[1:3], (), (), 0.1), "fine")
