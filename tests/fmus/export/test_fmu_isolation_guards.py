"""The bundle an FMU carries (fmus/export/bundle.py), read back file by file, and its two guards:
the kernels' library built when it is missing (and only then), and the check that no absolute
import of a bundled name is left after the rewriting (issue 31: seed 3601's survivors [3] and
[13]; every exported value read back exactly).  No FMU is built: fast."""
from __future__ import annotations

import hashlib

import pytest

import kernels
from fmus.export import bundle
from fmus.export.bundle import _build_kernels, _check_rewritten, bundle_name, rewrite_imports, source_files


@pytest.mark.parametrize("source, line, left", [
    (b"from plant.x import y\n", 1, "['plant.x']"),
    (b"import os\nimport fmus.status\n", 2, "['fmus.status']"),
    (b"import os, motor as m\n", 1, "['motor']"),
    (b"def f():\n    from controller import law\n", 2, "['controller']"),
])
def test_an_absolute_import_of_a_bundled_name_left_is_an_error_naming_file_and_line(source, line, left):
    """Catches the guard looking at relative imports instead of absolute ones (seed 3601's [13]:
    ``node.level == 1``), or at neither."""
    with pytest.raises(AssertionError) as raised:
        _check_rewritten(source, "mod.py")
    assert str(raised.value) == f"mod.py:{line}: import of {left} not rewritten"


def test_relative_rewritten_and_other_imports_pass_the_guard():
    """Relative imports (``from . import x``, ``from .plant import y``: inside the bundle), the
    private package's and other packages' imports are no error."""
    _check_rewritten(b"from . import sibling\nfrom .plant import y\nfrom .. import fmus\n"
                     b"import P.plant.x, P.plant as plant\nfrom P.fmus.slave.base import MIN_STEP\n"
                     b"import os, numpy as np\nfrom planter import x\n", "ok.py")


def test_the_bundle_holds_every_source_rewritten_and_every_other_file_as_it_is(tmp_path):
    """write_bundle's package read back: the files are exactly :func:`source_files`' (plus the
    package's ``__init__.py``), each Python file is its source with the imports rewritten, each
    other file (the kernels' library and C sources) byte for byte the repository's.  Catches a
    file left out or added, a source bundled unrewritten, and the library stale or missing."""
    package = bundle.write_bundle(tmp_path)
    assert package == tmp_path / bundle_name()
    expected = dict(source_files())
    written = {p.relative_to(package).as_posix() for p in package.rglob("*") if p.is_file()}
    assert written == set(expected) | {"__init__.py"}
    assert "kernels/libparcosim_kernels.so" in expected
    for relative, path in expected.items():
        data = (package / relative).read_bytes()
        if path.suffix == ".py":
            assert data == rewrite_imports(path.read_bytes(), package.name, relative), relative
        else:
            assert hashlib.sha256(data).digest() == hashlib.sha256(path.read_bytes()).digest(), relative
    assert (package / "__init__.py").read_text().startswith(f'"""parcosim\'s model code bundled into an FMU as '
                                                           f'{package.name}')


@pytest.fixture
def library_at(monkeypatch, tmp_path):
    """kernels.LIBRARY moved to a temporary path (present or not, as the test makes it), the
    loading left out and kernels.build.build recorded, not run."""
    from kernels import build

    built = []
    monkeypatch.setattr(kernels, "library", lambda: None)
    monkeypatch.setattr(kernels, "LIBRARY", tmp_path / "libparcosim_kernels.so")
    monkeypatch.setattr(build, "build", lambda *args, **kwargs: built.append((args, kwargs)))
    return kernels.LIBRARY, built


def test_a_missing_library_is_built_for_the_bundle_and_a_present_one_is_not(library_at):
    """``$PARCOSIM_KERNELS_LIB`` may have loaded another build: the bundle's own library is
    built when it is missing, and an existing one is not built again at every FMU's build
    (issue 27: starting an FMU compiles nothing, building one compiles only what is missing).
    Catches the test of existence inverted (seed 3601's [3]) or dropped."""
    path, built = library_at
    _build_kernels()
    assert built == [((), {})]
    path.write_bytes(b"a library")
    _build_kernels()
    assert built == [((), {})]
