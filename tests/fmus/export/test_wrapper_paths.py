"""Where ``fmus.export.wrapper`` keeps its compiled wrapper and which compiler it takes, as its
docstrings say: ``$PARCOSIM_CACHE``, else ``$XDG_CACHE_HOME/parcosim``, else
``~/.cache/parcosim``, each with the folder ``fmi2-wrapper``; ``$CC`` (its first word) if found,
else ``cc``, else ``gcc`` (issue 31: each default read back, not only the one the test machine
happens to take).  Nothing is compiled."""
from __future__ import annotations

import os
from pathlib import Path

import pytest

from fmus.export import wrapper


def test_the_cache_is_parcosim_cache_then_xdg_then_home_each_with_the_wrapper_folder(tmp_path, monkeypatch):
    """Catches the ``fmi2-wrapper`` folder dropped, a variable read under another name, the
    order of the three swapped, and ``parcosim`` left out below XDG or the home folder."""
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    monkeypatch.setenv("PARCOSIM_CACHE", str(tmp_path / "own"))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert wrapper.cache_dir() == tmp_path / "own" / "fmi2-wrapper"
    monkeypatch.setenv("PARCOSIM_CACHE", "")   # empty: not set (a shell's PARCOSIM_CACHE= )
    assert wrapper.cache_dir() == tmp_path / "xdg" / "parcosim" / "fmi2-wrapper"
    monkeypatch.delenv("PARCOSIM_CACHE")
    monkeypatch.delenv("XDG_CACHE_HOME")
    assert wrapper.cache_dir() == tmp_path / "home" / ".cache" / "parcosim" / "fmi2-wrapper"


def _tools(folder: Path, *names: str) -> Path:
    """Executables ``names`` (empty shell scripts) in ``folder``."""
    folder.mkdir()
    for name in names:
        path = folder / name
        path.write_text("#!/bin/sh\n")
        path.chmod(0o755)
    return folder


def test_the_compiler_is_cc_variable_first_word_then_cc_then_gcc(tmp_path, monkeypatch):
    """Catches ``$CC`` ignored, its arguments taken as part of its name (``ccache gcc``), an
    unfound ``$CC`` returned or taken as no compiler, and gcc taken before cc."""
    bin_ = _tools(tmp_path / "bin", "cc", "gcc", "ccache")
    monkeypatch.setenv("PATH", str(bin_))
    monkeypatch.setenv("CC", "ccache gcc -m64")
    assert wrapper.compiler() == str(bin_ / "ccache")
    monkeypatch.setenv("CC", "no-such-compiler")
    assert wrapper.compiler() == str(bin_ / "cc")
    monkeypatch.delenv("CC")
    assert wrapper.compiler() == str(bin_ / "cc")
    (bin_ / "cc").unlink()
    assert wrapper.compiler() == str(bin_ / "gcc")
    (bin_ / "gcc").unlink()
    assert wrapper.compiler() is None


def test_the_cache_key_changes_with_the_compiler_and_is_sixteen_hex_digits():
    """The key names the cached file: another compiler must not reuse it.  Catches the
    compiler left out of the hash and a key of another length."""
    a, b = wrapper._key("/usr/bin/cc"), wrapper._key("/usr/bin/clang")
    assert a != b and a == wrapper._key("/usr/bin/cc")
    assert len(a) == 16 and int(a, 16) >= 0 and a == a.lower()


@pytest.mark.skipif(os.name != "posix", reason="POSIX executables")
def test_no_compiler_is_a_warning_naming_the_missing_tool_and_no_wrapper(tmp_path, monkeypatch):
    """Catches a missing compiler taken for a failed build (an exception) or returned as a path."""
    monkeypatch.setenv("PATH", str(_tools(tmp_path / "empty")))
    monkeypatch.delenv("CC", raising=False)
    monkeypatch.setattr(wrapper, "_warned", False)
    with pytest.warns(RuntimeWarning, match=r"no C compiler \(cc or gcc\) on the PATH"):
        assert wrapper.compiled_wrapper() is None
