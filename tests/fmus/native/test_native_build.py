"""The native FMUs as files (issue 28, items 1, 2, 4): what their binaries link, `fmpy
validate`, a rebuild from the sources they carry, their GUIDs and states against the twins'."""
from __future__ import annotations

import math
import shutil
import struct
import subprocess
import zipfile

import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.validation import validate_fmu

from fmus.native.build import compile_command, platform_folder
from fmus.native.models import NATIVE
from tests.support.fmu_calls import Driver

pytestmark = [pytest.mark.fmu]

MODELS = sorted(NATIVE)
#: With the native ClosedLoop of a scene (``export-fmu --native``, the fixture ``native_loop_fmu``).
WITH_LOOP = MODELS + ["ClosedLoop"]
#: What a native FMU's binary may need: the C library and libm (and the loader itself).
ALLOWED = {"libc.so.6", "libm.so.6", "ld-linux-x86-64.so.2"}
#: The strict warnings of the kernels' own build: the sources must pass them on any compiler.
STRICT = ("-Wall", "-Wextra", "-Werror", "-Wshadow")


def needed(binary) -> set:
    out = subprocess.run(["readelf", "-d", str(binary)], capture_output=True, text=True, check=True).stdout
    return {line.split("[")[1].split("]")[0] for line in out.splitlines() if "(NEEDED)" in line}


@pytest.fixture
def fmu_of(request):
    """model -> its native FMU (the ClosedLoop's fixture for "ClosedLoop"), built on first use."""
    def of(model):
        return request.getfixturevalue("native_loop_fmu") if model == "ClosedLoop" else \
            request.getfixturevalue("native_fmus")[model]
    return of


@pytest.mark.parametrize("model", WITH_LOOP)
def test_binary_needs_only_libc_and_libm_and_the_fmu_validates(model, fmu_of, tmp_path):
    """Catches a native FMU binary that links libpython (or anything but libc and libm), an FMU fmpy's
    validation refuses, or one that claims to need an execution tool."""
    unzipped = extract(str(fmu_of(model)), str(tmp_path))
    binary = tmp_path / "binaries" / platform_folder() / f"{model}.so"
    assert needed(binary) <= ALLOWED
    assert "libpython" not in subprocess.run(["ldd", str(binary)], capture_output=True, text=True).stdout
    assert validate_fmu(str(fmu_of(model))) == []
    md = read_model_description(unzipped)
    assert md.coSimulation.needsExecutionTool is False


def _rebuilt(fmu, tmp_path):
    """An unzipped copy of ``fmu`` whose binary was compiled from its sources/ alone (plus
    fmpy's standard FMI 2.0 headers), with the kernels' strict warnings as errors."""
    folder = tmp_path / "rebuilt"
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    sources = tmp_path / "only_sources"
    shutil.copytree(folder / "sources", sources)
    model = read_model_description(str(fmu)).coSimulation.modelIdentifier
    binary = folder / "binaries" / platform_folder() / f"{model}.so"
    binary.unlink()
    command = compile_command(sources, binary)
    subprocess.run([command[0], *STRICT, *command[1:]], check=True, capture_output=True)
    return folder


@pytest.mark.parametrize("model", WITH_LOOP)
def test_fmu_compiled_from_its_own_sources_runs_as_shipped(model, fmu_of, tmp_path):
    """Catches shipped sources that are not the ones the binary was built from (a rebuild from the FMU's
    sources/ steps differently)."""
    fmu = fmu_of(model)
    rebuilt = _rebuilt(fmu, tmp_path)
    shipped = simulate_fmu(str(fmu), stop_time=0.2, output_interval=1e-3, step_size=1e-3)
    again = simulate_fmu(str(rebuilt), stop_time=0.2, output_interval=1e-3, step_size=1e-3)
    for name in shipped.dtype.names:
        if np.issubdtype(shipped[name].dtype, np.number):
            assert np.array_equal(shipped[name], again[name]), name


def test_cmake_builds_the_binary_from_the_sources(native_fmus, tmp_path):
    """Catches an FMU's sources/ folder that does not build with its own CMakeLists (a missing file or
    header path)."""
    cmake = shutil.which("cmake")
    if cmake is None:
        pytest.skip("no cmake")
    from fmus.native.build import fmi_headers

    model = MODELS[0]
    with zipfile.ZipFile(native_fmus[model]) as z:
        z.extractall(tmp_path / "fmu")
    build = tmp_path / "build"
    subprocess.run([cmake, f"-DFMI_HEADERS={fmi_headers()}", "-S", str(tmp_path / "fmu" / "sources"), "-B",
                    str(build)], check=True, capture_output=True)
    subprocess.run([cmake, "--build", str(build)], check=True, capture_output=True)
    assert (build / f"{model}.so").exists()


@pytest.mark.parametrize("model", MODELS)
def test_states_of_the_twin_and_damaged_states_are_refused(model, native_fmus, twin_fmus):
    """Catches a native FMU that deserialises its pythonfmu twin's state, a flipped byte, a truncated state
    or another GUID's, or a twin that takes the native state."""
    twin, native = Driver(twin_fmus[model]), Driver(native_fmus[model])
    assert twin.md.guid != native.md.guid
    for d in (twin, native):
        d.run([("setup", 0.0), ("enter",), ("exit",)])
    twin_bytes = twin.fmu.serializeFMUstate(twin.fmu.getFMUstate())
    own = native.fmu.serializeFMUstate(native.fmu.getFMUstate())
    flipped = bytearray(own)
    flipped[len(own) // 2] ^= 0x40
    other_guid = bytes(own).replace(native.md.guid.encode(), twin.md.guid.encode())
    for data, says in ((twin_bytes, "not a serialised parcosim native FMU state"), (bytes(flipped), "checksum"),
                       (own[:-9], "long"), (other_guid, "")):
        step = native.call("bytes", "x", data)
        step = native.call("deserialize", "x")
        assert step.status == 3 and says in step.messages[0][2], step.messages
    # the twin refuses the native state just as well
    twin.call("bytes", "n", own)
    assert twin.call("deserialize", "n").status == 3
    twin.close()
    native.close()


def test_state_with_a_changed_configuration_word_is_refused(native_fmus):
    """A forged state whose design words differ (checksum recomputed) is refused by name."""
    from fmus.native import state_bytes

    native = Driver(native_fmus["Derivator"])
    native.run([("setup", 0.0), ("enter",), ("exit",)])
    own = native.fmu.serializeFMUstate(native.fmu.getFMUstate())
    forged = state_bytes.with_data_word(own, 5, 123.0)
    native.call("bytes", "f", forged)
    step = native.call("deserialize", "f")
    assert step.status == 3 and "word 5 of the derivator's buffer" in step.messages[0][2]
    native.call("bytes", "g", state_bytes.with_data_word(own, 5, state_bytes.data_words(own)[5]))
    assert native.call("deserialize", "g").status == 0    # the same bytes, checksum recomputed: accepted
    native.close()


def test_controller_state_with_forged_words_is_refused(native_fmus):
    """The position controller's data: the law's state (10 words), its parameters (the set-up
    of this instance's parameters: a gain forged is refused), the delay queue (rows past
    delay_steps zero, the others finite), the fallback count; and a String value not UTF-8
    (the fuzz's flips made one of the error text, which a message then echoed); checksum
    recomputed each time."""
    from controller import law
    from fmus.native import state_bytes

    native = Driver(native_fmus["PositionController"])
    native.run([("set", {"strategy": "TCMDx", "delay_steps": 1}), ("setup", 0.0), ("enter",), ("exit",)])
    own = native.fmu.serializeFMUstate(native.fmu.getFMUstate())
    words = state_bytes.data_words(own)
    assert words[law.BUF_KP] == 60.0 ** 2 and words[law.STATE["k"].start] == 103.0   # TCMDx's (Table 8)
    queue = law.STATE_SIZE + law.PARAMS_SIZE
    for word, value, says in ((law.BUF_KP, 3601.0, "configuration words"), (law.BUF_MODEL, 2.0, "configuration"),
                              (law.BUF_INTEGRAL, math.nan, "state word"), (queue + 1, math.inf, "delay queue"),
                              (queue + 4, 1.0, "delay queue"), (len(words) - 3, 0.5, "fallback count")):
        native.call("bytes", "f", state_bytes.with_data_word(own, word, value))
        step = native.call("deserialize", "f")
        assert step.status == 3 and says in step.messages[0][2], (word, step.messages)
    native.call("bytes", "g", state_bytes.with_data_word(own, law.BUF_INTEGRAL, 0.25))
    assert native.call("deserialize", "g").status == 0     # the run state may be any finite value
    # a String value that is not UTF-8 (the error text, which messages echo) is refused
    native.call("set", {"q1": math.nan})
    assert native.call("step", 0.0, 1e-3).status == 2     # refused: "error" holds why
    refused = bytearray(native.fmu.serializeFMUstate(native.fmu.getFMUstate()))
    refused[bytes(refused).index(b"input q1 = nan")] = 0x9F
    struct.pack_into("=Q", refused, len(refused) - 8, state_bytes.fnv1a(bytes(refused[:-8])))
    native.call("bytes", "u", bytes(refused))
    step = native.call("deserialize", "u")
    assert step.status == 3 and "do not fit" in step.messages[0][2], step.messages
    native.close()


@pytest.mark.parametrize("model", ["BalanceController", "CurrentObserver", "Derivator", "PositionController"])
def test_state_with_a_forged_substep_counter_is_refused(model, native_fmus):
    """The sub-step counter (the model data's last two words: sub-step k, n = T / h) must be
    whole with 0 <= k < n, or both 0; a forged one (checksum recomputed) is refused by name,
    the true one (taken mid-period at h = T / 4) accepted and stepped on."""
    from fmus.native import state_bytes

    native = Driver(native_fmus[model])
    h = float(native.variables["T"].start) / 4
    native.run([("setup", 0.0), ("enter",), ("exit",), ("step", 0.0, h), ("step", h, h)])
    own = native.fmu.serializeFMUstate(native.fmu.getFMUstate())
    words = state_bytes.data_words(own)
    last = len(words) - 2
    assert (words[last], words[last + 1]) == (2.0, 4.0)   # the next sub-step, n
    for k, n in ((4.0, 4.0), (1.5, 4.0), (-1.0, 4.0), (1.0, 0.0), (0.0, 2.5), (math.nan, 4.0)):
        native.call("bytes", "f", state_bytes.with_data_word(state_bytes.with_data_word(own, last, k), last + 1, n))
        step = native.call("deserialize", "f")
        assert step.status == 3 and "sub-step counter" in step.messages[0][2], (k, n)
    native.call("bytes", "g", own)
    assert native.call("deserialize", "g").status == 0
    assert native.call("setstate", "g").status == 0
    assert native.call("step", 2 * h, h).status == 0
    native.close()


def test_plant_state_with_forged_configuration_or_state_words_is_refused(native_fmus):
    """FiveBarPlant's model data: the kernel's parameters and settings (configuration: equal to
    what the instance's parameters give) and the state q, dq (finite).  A forged l0 word, a
    forged RK4 substep count and a NaN in the state are refused by name (checksum recomputed);
    the true state, taken after two steps, is accepted and stepped on."""
    from fmus.native import state_bytes

    native = Driver(native_fmus["FiveBarPlant"])
    native.run([("setup", 0.0), ("enter",), ("exit",), ("step", 0.0, 1e-3), ("step", 1e-3, 1e-3)])
    own = native.fmu.serializeFMUstate(native.fmu.getFMUstate())
    words = state_bytes.data_words(own)
    assert words[0] == 0.05 and words.size == 22 + 7 + 14     # l0 first; params, settings, q, dq
    substeps, x = 22 + 1, 22 + 7
    for index, value, says in ((0, 0.06, "configuration words"), (substeps, 2.0, "configuration words"),
                               (x + 3, math.nan, "state word 3 = nan")):
        native.call("bytes", "f", state_bytes.with_data_word(own, index, value))
        step = native.call("deserialize", "f")
        assert step.status == 3 and says in step.messages[0][2], (index, step.messages)
    native.call("bytes", "g", state_bytes.with_data_word(own, x, words[x]))
    assert native.call("deserialize", "g").status == 0
    assert native.call("setstate", "g").status == 0
    assert native.call("step", 2e-3, 1e-3).status == 0


def test_drive_state_with_forged_words_is_refused_and_its_true_state_goes_on(native_fmus):
    """DCMotorDrive's model data (pcn_drive_data: R, L, method, has_lugre, then the kernel's
    pc_drive, pc_controller, pc_lugre, then the internal observer): a forged configuration word
    (kt, the design's alpha), a sub-step past T / h, coefficients not of the step length and
    a non-finite current are refused by name (checksum recomputed); the true state, taken
    mid-period at h = T / 4, is accepted and stepped on."""
    import kernels
    from fmus.native import state_bytes
    from motor import kernel

    native = Driver(native_fmus["DCMotorDrive"])
    h = float(native.variables["T"].start) / 4
    native.run([("setup", 0.0), ("enter",), ("exit",), ("step", 0.0, h), ("step", h, h)])
    own = native.fmu.serializeFMUstate(native.fmu.getFMUstate())
    words = state_bytes.data_words(own)
    drive = {name: 4 + s.start for name, s in kernel.DRIVE.items()}
    alpha = 4 + kernels.size(kernel.DRIVE) + kernel.CONTROLLER["alpha"].start
    assert (words[drive["phase"]], words[drive["substeps"]], words[drive["h"]]) == (2.0, 4.0, h)
    for index, value, says in ((drive["kt"], 0.07, "configuration words"), (alpha, 1.0, "configuration words"),
                               (drive["phase"], 4.0, "sub-step 4.0"), (drive["a"], 0.5, "coefficients"),
                               (drive["i"], math.inf, "state word 0 is inf")):
        native.call("bytes", "f", state_bytes.with_data_word(own, index, value))
        step = native.call("deserialize", "f")
        assert step.status == 3 and says in step.messages[0][2], (index, step.messages)
    native.call("bytes", "g", own)
    assert native.call("deserialize", "g").status == 0
    assert native.call("setstate", "g").status == 0
    assert native.call("step", 2 * h, h).status == 0
    native.close()


def test_actuated_plant_state_with_forged_words_is_refused(native_fmus):
    """ActuatedFiveBarPlant's model data: the plant's configuration (29 words), z = (q, dq, i1,
    i2), the two motor rows (8 words each), then the two drives.  A forged motor row (drive 2's
    R), a NaN current in z and a forged drive word (drive 1's kt) are refused by name; the true
    state, taken after two steps, is accepted and stepped on."""
    from fmus.native import state_bytes

    native = Driver(native_fmus["ActuatedFiveBarPlant"])
    native.run([("setup", 0.0), ("enter",), ("exit",), ("set", {"i_ref1": 0.2, "i_hat1": 0.1}),
                ("step", 0.0, 1e-3), ("step", 1e-3, 1e-3)])
    own = native.fmu.serializeFMUstate(native.fmu.getFMUstate())
    words = state_bytes.data_words(own)
    z, motors = 29, 29 + 16
    drive1 = motors + 16
    assert words[z + 14] != 0.0 and words[motors + 8] == 1.0    # i1 flows; row 2 drives joint 1 (q2)
    kt1 = next(k for k in range(drive1, words.size) if words[k] == words[motors + 3])   # kt of motor row 1
    for index, value, says in ((motors + 8 + 1, 2.0, "motor rows"), (z + 15, math.nan, "state word 15 = nan"),
                               (kt1, 0.07, "drive's configuration words")):
        native.call("bytes", "f", state_bytes.with_data_word(own, index, value))
        step = native.call("deserialize", "f")
        assert step.status == 3 and says in step.messages[0][2], (index, step.messages)
    native.call("bytes", "g", own)
    assert native.call("deserialize", "g").status == 0
    assert native.call("setstate", "g").status == 0
    assert native.call("step", 2e-3, 1e-3).status == 0
    native.close()
