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
