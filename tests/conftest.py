"""Shared fixtures: the FMUs are built once per test session.

Markers (pyproject.toml): ``slow`` on whole files by their ``pytestmark`` (CI runs ``pytest -m
"not slow"``, ``pytest -m slow`` the rest), ``fmu`` on files about FMUs and, here, on every test that uses
an FMU fixture, ``tools`` on files that drive a third-party tool (Ecos, libcosim, MuJoCo,
cosmic-ray, a sanitizer build); ``-m "not slow and not fmu and not tools and not sweep"`` is the quick subset.
The test files sit in folders by the layer they test (tests/layout_rules.py).
"""
import os
import shutil
import tempfile

import pytest


@pytest.fixture(scope="session", autouse=True)
def session_temp_folder(tmp_path_factory):
    """Every temporary file or folder made through :mod:`tempfile` during the session, by a test,
    the code it runs or a process it starts (``TMPDIR``), goes in one folder, removed at the end:
    a test or a library that forgets to clean up (an FMU unzipped by fmpy and never removed)
    cannot fill the machine's temp folder, run after run."""
    folder = tmp_path_factory.mktemp("tempfile")
    before = tempfile.tempdir, os.environ.get("TMPDIR")
    tempfile.tempdir, os.environ["TMPDIR"] = str(folder), str(folder)
    yield folder
    tempfile.tempdir = before[0]
    if before[1] is None:
        os.environ.pop("TMPDIR", None)
    else:
        os.environ["TMPDIR"] = before[1]
    shutil.rmtree(folder, ignore_errors=True)


@pytest.fixture(scope="session")
def built_fmus(tmp_path_factory):
    """Model name -> path of every FMU ``parcosim build`` makes, built into a temporary directory."""
    from fmus.export.build import build_all

    out = tmp_path_factory.mktemp("fmus")
    return {path.stem: path for path in build_all(out)}


def pytest_collection_modifyitems(config, items):
    """A test that uses an FMU fixture (one named ``*_fmu`` or ``*_fmus``: :func:`built_fmus`,
    :func:`native_fmus` ..., directly or through another fixture) is an ``fmu`` test."""
    for item in items:
        if any(name.endswith(("_fmu", "_fmus")) for name in getattr(item, "fixturenames", ())):
            item.add_marker(pytest.mark.fmu)


@pytest.fixture(scope="session")
def native_fmus(tmp_path_factory):
    """Model name -> path of every native FMU (``parcosim build --native``)."""
    from fmus.native.build import build_native_all

    out = tmp_path_factory.mktemp("native")
    return {path.stem: path for path in build_native_all(out)}


@pytest.fixture(scope="session")
def twin_fmus(tmp_path_factory):
    """Model name -> path of the pythonfmu FMU of every model that has a native FMU."""
    from fmus.export.build import build_fmu
    from fmus.native.models import NATIVE

    out = tmp_path_factory.mktemp("twins")
    return {model: build_fmu(model, out) for model in NATIVE}


#: The scene of the native whole-loop FMU's tests (``parcosim export-fmu SCENE OUT.fmu --native``).
LOOP_SCENE = "bench_circle_TCMDx"


@pytest.fixture(scope="session")
def native_loop_fmu(tmp_path_factory):
    """The native ClosedLoop of :data:`LOOP_SCENE`, written by the command line."""
    from parcosim.cli import main

    path = tmp_path_factory.mktemp("native_loop") / "ClosedLoop.fmu"
    assert main(["export-fmu", LOOP_SCENE, str(path), "--native"]) == 0
    return path


@pytest.fixture(scope="session")
def twin_loop_fmu(tmp_path_factory):
    """The pythonfmu ClosedLoop of :data:`LOOP_SCENE` (``parcosim export-fmu``)."""
    from fmus.systemfmu.export import export_fmu
    from scenarios.scenes import get_scene

    return export_fmu(get_scene(LOOP_SCENE).system, tmp_path_factory.mktemp("twin_loop") / "ClosedLoop.fmu")
