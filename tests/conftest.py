"""Shared fixtures: the FMUs are built once per test session."""
import pytest


@pytest.fixture(scope="session")
def built_fmus(tmp_path_factory):
    """Model name -> path of every FMU ``parcosim build`` makes, built into a temporary directory."""
    from fmus.build import build_all

    out = tmp_path_factory.mktemp("fmus")
    return {path.stem: path for path in build_all(out)}


@pytest.fixture(scope="session")
def native_fmus(tmp_path_factory):
    """Model name -> path of every native FMU (``parcosim build --native``)."""
    from fmus.native.build import build_native_all

    out = tmp_path_factory.mktemp("native")
    return {path.stem: path for path in build_native_all(out)}


@pytest.fixture(scope="session")
def twin_fmus(tmp_path_factory):
    """Model name -> path of the pythonfmu FMU of every model that has a native FMU."""
    from fmus.build import build_fmu
    from fmus.native.models import NATIVE

    out = tmp_path_factory.mktemp("twins")
    return {model: build_fmu(model, out) for model in NATIVE}
