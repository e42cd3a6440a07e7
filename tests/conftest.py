"""Shared fixtures: the FMUs are built once per test session."""
import pytest


@pytest.fixture(scope="session")
def built_fmus(tmp_path_factory):
    """Model name -> path of every FMU ``parcosim build`` makes, built into a temporary directory."""
    from fmus.build import build_all

    out = tmp_path_factory.mktemp("fmus")
    return {path.stem: path for path in build_all(out)}
