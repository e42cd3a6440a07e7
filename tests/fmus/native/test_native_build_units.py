"""fmus/native/build.py's small rules without building an FMU: the binaries folder of each FMI
version (the standard's names, as fmpy spells them), the versions refused before anything is
written, and the compile flags that keep a native FMU bit for bit with the kernels' library."""
from __future__ import annotations

import fmpy
import pytest

from fmus.native import build


def test_the_binaries_folder_is_fmi2s_by_default_and_fmi3s_platform_tuple_for_3():
    """FMI 2.0 names the folder by platform (linux64 ...), FMI 3.0 by its tuple (x86_64-linux ...)."""
    assert build.platform_folder() == build.platform_folder(2) == fmpy.platform
    assert build.platform_folder(3) == fmpy.platform_tuple
    assert fmpy.platform != fmpy.platform_tuple


@pytest.mark.parametrize("version", [1, 4, "2"])
def test_an_fmi_version_other_than_2_or_3_is_refused_naming_it_before_anything_is_written(version, tmp_path):
    with pytest.raises(ValueError) as refused:
        build.build_native_fmu("Trajectory", tmp_path, fmi_version=version)
    assert str(refused.value) == f"FMI version {version!r}: the native FMUs are FMI 2.0 or 3.0 (2 or 3)"
    assert list(tmp_path.iterdir()) == []


def test_the_native_compile_flags_keep_the_kernels_floating_point_rules():
    """No FMA contraction and no fast math, as kernels/build.py compiles the library the twins
    use; position independent, hidden symbols, C11; the command links libm and refuses
    undefined symbols (the binary needs only libc and libm)."""
    from kernels import build as kernels_build

    for flag in ("-ffp-contract=off", "-fno-fast-math", "-std=c11", "-fPIC"):
        assert flag in build.CFLAGS and flag in kernels_build.FLAGS, flag
    assert "-fvisibility=hidden" in build.CFLAGS
    command = build.compile_command(build.HERE, build.HERE / "x.so", compiler="gcc-x")
    assert command[0] == "gcc-x" and command[1:1 + len(build.CFLAGS)] == list(build.CFLAGS)
    assert command[-4:] == ["-o", str(build.HERE / "x.so"), "-Wl,--no-undefined", "-lm"]
    assert "-shared" in command and f"-I{build.fmi_headers()}" in command
    assert [c for c in command if c.endswith(".c")] == sorted(str(p) for p in build.HERE.glob("*.c"))


def test_two_sources_of_one_name_are_refused_naming_them_before_anything_is_written(tmp_path):
    """sources/ is flat: an adapter part named as a generic file (or as a generated one) would
    overwrite it.  Catches the check counting names otherwise (the FMI layer or the generated
    files left out of it) and a refusal that does not name the files."""
    first, second = tmp_path / "a" / "pcn_core.c", tmp_path / "b" / "pcn_core.c"
    for path in (first, second):
        path.parent.mkdir()
        path.write_text("/* */\n")
    target = tmp_path / "out" / "M.fmu"
    with pytest.raises(build.NativeBuildError) as refused:
        build.package("M", None, [], {}, {}, [first, second], {}, target)
    assert str(refused.value).startswith("M: two source files share a name: ")
    assert str(refused.value).count("pcn_core.c") == 2
    for generated in ({"fmi2_native.c": "x"}, {"pcn_core.c": "x"}):   # the FMI layer's, a given file's
        with pytest.raises(build.NativeBuildError, match=r"^M: two source files share a name: "):
            build.package("M", None, [], {}, {}, [first], generated, target)
    assert not target.parent.exists()
