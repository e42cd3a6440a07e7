"""parcosim's FMI 2.0 wrapper (fmus/export/wrapper/parcosim_fmi2.c) under hostile and careless use.

Every case runs in its own Python process (tests/support/fmi2raw.py drives the FMU's
binary through ctypes), so that a crash of the importing process is a failed test, not
a dead pytest.  The cases and their outcomes are the table of docs/extremes.md, "The FMI
wrapper".
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
import zipfile
from pathlib import Path

import pytest

from fmus.export.wrapper import compiled_wrapper, has_wrapper, install_wrapper
from tests.support.paths import ROOT

pytestmark = [pytest.mark.fmu, pytest.mark.skipif(compiled_wrapper(quiet=True) is None,
                                                   reason="no C compiler: the FMUs keep pythonfmu's wrapper")]

PRELUDE = """
import json, os, sys
sys.path.insert(0, {support!r})
from fmi2raw import RawFmu, OK, DISCARD, ERROR, FATAL
def report(**values):
    print("RESULT " + json.dumps(values), flush=True)
"""

PROBER = '''
import os, signal, time
from pythonfmu import Fmi2Slave, Fmi2Causality, Fmi2Variability, Boolean, Integer, Real, String
from fmus.slave.base import FmiError


class Prober(Fmi2Slave):
    """Fails on request: parameter ``action`` = "<init|step>:<fmierror|runtime|interrupt|sigint|discard>"."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.action, self.x, self.y, self.n, self.flag = "", 0.0, 0.0, 0, False
        self.register_variable(String("action", causality=Fmi2Causality.parameter, variability=Fmi2Variability.tunable))
        self.register_variable(Real("x", causality=Fmi2Causality.input))
        self.register_variable(Real("y", causality=Fmi2Causality.output))
        self.register_variable(Integer("n", causality=Fmi2Causality.output))
        self.register_variable(Boolean("flag", causality=Fmi2Causality.input))

    def _act(self, where):
        what = self.action.partition(where + ":")[2] if self.action.startswith(where + ":") else ""
        if what == "fmierror":
            raise FmiError(f"{where} refused: x = {self.x!r}")
        if what == "runtime":
            raise RuntimeError("boom %s%n")
        if what == "interrupt":
            raise KeyboardInterrupt
        if what == "sigint":
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(5)
        return what != "discard"

    def exit_initialization_mode(self):
        self._act("init")

    def do_step(self, current_time, step_size):
        if not self._act("step"):
            return False
        self.y = self.x + current_time + step_size
        self.n += 1
        return True
'''


def run_case(code: str, stderr=subprocess.PIPE, timeout: float = 120) -> dict:
    """Run ``code`` (after PRELUDE) in a fresh Python; assert it exited 0; its report()."""
    source = PRELUDE.format(support=str(ROOT / "tests" / "support")) + textwrap.dedent(code)
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    run = subprocess.run([sys.executable, "-c", source], stdout=subprocess.PIPE, stderr=stderr, env=env,
                         timeout=timeout, text=True)
    errors = run.stderr if isinstance(run.stderr, str) else ""
    assert run.returncode == 0, f"exit status {run.returncode}\nstdout:\n{run.stdout}\nstderr:\n{errors[-3000:]}"
    lines = [line for line in run.stdout.splitlines() if line.startswith("RESULT ")]
    assert lines, f"no result\nstdout:\n{run.stdout}\nstderr:\n{errors[-3000:]}"
    return json.loads(lines[-1][len("RESULT "):])


def unzip(fmu, where: Path) -> Path:
    where.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(fmu) as z:
        z.extractall(where)
    return where


@pytest.fixture(scope="module")
def drive(built_fmus, tmp_path_factory) -> Path:
    """DCMotorDrive unzipped (String parameters mode, method, torque_output)."""
    return unzip(built_fmus["DCMotorDrive"], tmp_path_factory.mktemp("drive"))


@pytest.fixture(scope="module")
def prober(tmp_path_factory) -> Path:
    """A small slave that raises on request, built by pythonfmu with parcosim's wrapper, unzipped."""
    from pythonfmu import FmuBuilder

    tmp = tmp_path_factory.mktemp("prober")
    script = tmp / "prober.py"
    script.write_text(PROBER)
    fmu = FmuBuilder.build_FMU(script, dest=tmp / "out")
    assert install_wrapper(fmu)
    return unzip(fmu, tmp / "unzipped")


def test_every_built_fmu_carries_parcosims_wrapper(built_fmus):
    """Catches a build that ships pythonfmu's own binary instead of parcosim's FMI wrapper."""
    assert built_fmus and all(has_wrapper(path) for path in built_fmus.values())
    result = run_case(f"""
        import ctypes, zipfile, tempfile
        with zipfile.ZipFile({str(built_fmus['Trajectory'])!r}) as z:
            path = z.extract("binaries/linux64/Trajectory.so", tempfile.mkdtemp())
        lib = ctypes.CDLL(path)
        lib.parcosimFmi2WrapperVersion.restype = ctypes.c_char_p
        lib.fmi2GetVersion.restype = ctypes.c_char_p
        report(version=lib.parcosimFmi2WrapperVersion().decode(), fmi=lib.fmi2GetVersion().decode())
    """)
    assert result["version"].startswith("parcosim-fmi2-wrapper ") and result["fmi"] == "2.0"


@pytest.mark.parametrize("where", ["parameter", "instance name"])
def test_printf_directives_reach_the_logger_as_text_never_as_a_format(drive, where):
    """pythonfmu: segfault (the message was the printf format).  Now: every message reaches
    the logger as a format without conversions (each '%' doubled), which prints the
    directives verbatim."""
    evil = "%s%s%s%s%n%n%p"
    result = run_case(f"""
        fmu = RawFmu({str(drive)!r})
        name = {evil!r}.encode() if {where!r} == "instance name" else b"drive"
        fmu.instantiate(name=name)
        statuses = fmu.start(mode={evil!r}.encode() if {where!r} == "parameter" else b"nonsense")
        step = fmu.step(0.0, 1e-3)
        report(statuses=statuses, step=step, formats=[m[2].decode() for m in fmu.messages],
               names=sorted({{m[4].decode() for m in fmu.messages}}), text=fmu.text())
        fmu.free()
    """)
    assert result["statuses"] == [0, 0, 0, 0] and result["step"] == 2
    assert result["formats"] and all("%" not in f.replace("%%", "") for f in result["formats"])
    if where == "parameter":
        assert evil in result["text"]
    else:
        assert result["names"] == [evil] and f"{evil}: initialisation refused" in result["text"]


def test_instance_name_that_is_not_utf8_is_decoded_with_replacement(drive):
    """Catches a wrapper that crashes on an instance name that is not UTF-8, or puts the name into the
    error output."""
    result = run_case(f"""
        fmu = RawFmu({str(drive)!r})
        ok = bool(fmu.instantiate(name=b"\\xff\\xfe"))
        statuses = fmu.start(mode=b"nonsense")
        step = fmu.step(0.0, 1e-3)
        status, error = fmu.get_string(fmu.vars["error"][0])
        report(ok=ok, statuses=statuses, step=step, error=error.decode())
        fmu.free()
    """)
    assert result["ok"] and result["step"] == 2
    assert result["error"].startswith("initialisation refused: mode must be one of")
    assert "\ufffd\ufffd" not in result["error"]   # the name is in the log line, not in error


@pytest.mark.parametrize("folder", ["caf\u00e9", "a#b", "x%41y", "with space", "\u00e9 #%41 %20"])
def test_fmu_unzipped_under_any_directory_name_instantiates(built_fmus, tmp_path, folder):
    """pythonfmu decoded only %20 of the resource URI: segfault.  Now every %XX is decoded."""
    where = unzip(built_fmus["Trajectory"], tmp_path / folder / "Trajectory")
    result = run_case(f"""
        fmu = RawFmu({str(where)!r})
        ok = bool(fmu.instantiate())
        statuses = fmu.start()
        step = fmu.step(0.0, 1e-3)
        report(ok=ok, statuses=statuses, step=step, uri=fmu.resource_uri().decode(), text=fmu.text())
        fmu.free()
    """)
    assert result["ok"], result["text"]
    assert result["statuses"] == [0, 0, 0] and result["step"] == 0


@pytest.mark.parametrize("uri, reason", [(b"http://example.org/resources/", "not a file: URI"),
                                         (b"file://server/share/resources", "host other than localhost"),
                                         (b"file:///tmp/%zz", "two hexadecimal digits")])
def test_resource_uris_that_are_not_local_files_are_refused_with_the_reason(drive, uri, reason):
    """Catches fmi2Instantiate accepting a remote, non-file or badly escaped resource URI (and then loading
    nothing) instead of refusing it with the reason."""
    result = run_case(f"""
        fmu = RawFmu({str(drive)!r})
        report(component=fmu.instantiate(uri={uri!r}), text=fmu.text(),
               statuses=[m[0] for m in fmu.messages])
    """)
    assert result["component"] is None and reason in result["text"] and result["statuses"] == [3]


def test_localhost_uri_form_is_accepted(drive):
    """Catches the file://localhost/ form of a resource URI (RFC 8089) refused."""
    result = run_case(f"""
        fmu = RawFmu({str(drive)!r})
        uri = b"file://localhost" + fmu.resource_uri()[len(b"file://"):]
        ok = bool(fmu.instantiate(uri=uri))
        report(ok=ok, statuses=fmu.start(), step=fmu.step(0.0, 1e-3))
        fmu.free()
    """)
    assert result == {"ok": True, "statuses": [0, 0, 0], "step": 0}


def test_unwritable_stderr_does_not_turn_refusals_into_failures(drive):
    """pythonfmu: fmi2Fatal, then segfaults.  Now: the refusal is fmi2Discard as with a
    writable stderr, later calls work, the process exits 0."""
    with open("/dev/full", "w") as full:
        result = run_case(f"""
            fmu = RawFmu({str(drive)!r})
            fmu.instantiate()
            statuses = fmu.start(mode=b"nonsense")
            steps = [fmu.step(0.0, 1e-3), fmu.step(0.0, 1e-3)]
            status, error = fmu.get_string(fmu.vars["error"][0])
            report(statuses=statuses, steps=steps, get=status, error=error.decode(),
                   terminate=fmu.lib.fmi2Terminate(fmu.c))
            fmu.free()
        """, stderr=full)
    assert result["statuses"] == [0, 0, 0, 0] and result["steps"] == [2, 2]
    assert result["get"] == 0 and "mode must be one of" in result["error"] and result["terminate"] == 0


def test_set_string_with_bytes_that_are_not_utf8_is_fmi2error_naming_the_variable(drive):
    """Catches bytes that are not UTF-8 set into a String (crash, or mojibake kept) instead of fmi2Error
    naming the variable with the value unchanged."""
    result = run_case(f"""
        fmu = RawFmu({str(drive)!r})
        fmu.instantiate()
        fmu.start()
        vr = fmu.vars["mode"][0]
        status = fmu.set_string(vr, b"cur\\xffrent")
        after = fmu.get_string(vr)
        report(status=status, value=after[1].decode(), text=fmu.text(), step=fmu.step(0.0, 1e-3))
        fmu.free()
    """)
    assert result["status"] == 3 and result["value"] == "current" and result["step"] == 0
    assert "'mode'" in result["text"] and "not UTF-8" in result["text"] and "0xff" in result["text"]


def test_invalid_and_wrongly_typed_value_references_are_fmi2error_naming_them(drive):
    """Catches an unknown or wrongly typed value reference, or a NULL array, that reads or writes memory
    instead of returning fmi2Error naming it."""
    result = run_case(f"""
        fmu = RawFmu({str(drive)!r})
        fmu.instantiate()
        fmu.start()
        mode = fmu.vars["mode"][0]
        statuses = [fmu.set_real(99999, 1.0), fmu.get_real(99999)[0], fmu.set_real(mode, 1.0),
                    fmu.get_real(mode)[0], fmu.get_string(fmu.vars["v_ref"][0])[0],
                    fmu.lib.fmi2SetReal(fmu.c, None, 1, None), fmu.lib.fmi2GetReal(fmu.c, None, 1, None)]
        report(statuses=statuses, text=fmu.text(), step=fmu.step(0.0, 1e-3))
        fmu.free()
    """)
    assert result["statuses"] == [3] * 7 and result["step"] == 0
    text = result["text"]
    assert "value reference 99999 is not a variable" in text
    assert f"('mode') is a String variable, not a Real" in text and "('v_ref') is a Real variable, not a String" in text
    assert "value reference array is NULL" in text


@pytest.mark.parametrize("action, message", [
    ("init:fmierror", "init refused: x = 0.0"),
    ("init:runtime", "RuntimeError: boom %s%n"),
    ("init:interrupt", "KeyboardInterrupt"),
    ("step:fmierror", "step refused: x = 0.0"),
    ("step:interrupt", "KeyboardInterrupt"),
    ("step:sigint", "KeyboardInterrupt"),
])
def test_an_exception_in_a_callback_is_fmi2error_and_the_instance_still_frees(prober, action, message):
    """FmiError, any other exception, KeyboardInterrupt and a real SIGINT: fmi2Error with the
    message logged (an FmiError's message alone); the instance keeps working and frees."""
    where = action.split(":")[0]
    result = run_case(f"""
        fmu = RawFmu({str(prober)!r})
        fmu.instantiate()
        statuses = fmu.start(action={action!r}.encode())
        step = fmu.step(0.0, 0.5)
        fmu.set_string(fmu.vars["action"][0], b"")
        again = fmu.step(0.0, 0.5)
        report(statuses=statuses, step=step, again=again, y=fmu.get_real(fmu.vars["y"][0]),
               text=fmu.text(), free_after=True)
        fmu.free()
        report(statuses=statuses, step=step, again=again, text=fmu.text(), freed=True)
    """)
    assert result["freed"]
    if where == "init":
        assert result["statuses"] == [0, 0, 0, 3] and result["step"] == 0
    else:
        assert result["statuses"] == [0, 0, 0, 0] and result["step"] == 3
    assert result["again"] == 0
    assert f"{'fmi2ExitInitializationMode' if where == 'init' else 'fmi2DoStep'}: {message}" in result["text"]
    assert "FmiError" not in result["text"]


def test_status_protocol_discard_state_reset_and_unsupported_calls(prober):
    """Catches a wrapper that maps a discard, a state round trip, a reset or an unsupported call to the wrong status."""
    result = run_case(f"""
        from ctypes import byref, c_double, c_int
        fmu = RawFmu({str(prober)!r})
        fmu.instantiate()
        fmu.start()
        lib, c = fmu.lib, fmu.c
        x, y, n = fmu.vars["x"][0], fmu.vars["y"][0], fmu.vars["n"][0]
        fmu.set_real(x, 2.0)
        first = fmu.step(0.0, 0.5)
        roundtrip = fmu.state_roundtrip()
        fmu.set_string(fmu.vars["action"][0], b"step:discard")
        discard = fmu.step(0.5, 0.5)
        last, status_kind = c_double(), c_int()
        real_status = lib.fmi2GetRealStatus(c, 2, byref(last))
        report(first=first, y=fmu.get_real(y)[1], roundtrip=roundtrip, discard=discard,
               last=[real_status, last.value], get_status=lib.fmi2GetStatus(c, 0, byref(status_kind)),
               cancel=lib.fmi2CancelStep(c), derivative=lib.fmi2GetDirectionalDerivative(c, None, 0, None, 0, None, None),
               reset=lib.fmi2Reset(c), x_after_reset=fmu.get_real(x)[1], text=fmu.text())
        fmu.free()
    """)
    assert result["first"] == 0 and result["y"] == 2.5 and result["roundtrip"] == [0] * 7
    assert result["discard"] == 2 and result["last"] == [0, 0.5] and result["get_status"] == 2
    assert result["cancel"] == 3 and result["derivative"] == 3 and "not supported" in result["text"]
    assert result["reset"] == 0 and result["x_after_reset"] == 0.0


def test_ten_runs_of_instantiate_initialise_step_free_exit_cleanly(drive):
    """pythonfmu: SIGABRT at interpreter exit in 8 of 10 runs of DCMotorDrive."""
    code = f"""
        fmu = RawFmu({str(drive)!r})
        fmu.instantiate()
        statuses = fmu.start() + [fmu.step(0.0, 1e-3)]
        fmu.free()
        report(statuses=statuses)
    """
    for _ in range(10):
        assert run_case(code)["statuses"] == [0, 0, 0, 0]


def test_instances_neither_grow_sys_path_nor_leak_objects(built_fmus, tmp_path):
    """Catches each instantiation adding to sys.path or leaving Python objects alive (200 instances then
    leak memory)."""
    where = unzip(built_fmus["Trajectory"], tmp_path / "Trajectory")
    result = run_case(f"""
        import gc
        fmu = RawFmu({str(where)!r})
        paths = list(sys.path)
        def cycle():
            fmu.instantiate(); fmu.start(); fmu.step(0.0, 1e-3); fmu.free()
        for _ in range(20):
            cycle()
        gc.collect()
        objects = len(gc.get_objects())
        for _ in range(200):
            cycle()
        gc.collect()
        report(same_path=paths == sys.path, objects=[objects, len(gc.get_objects())])
    """)
    assert result["same_path"]    # the bundle loads under its own name, without sys.path
    assert result["objects"][1] - result["objects"][0] < 50, result["objects"]


def test_without_a_compiler_fmus_keep_pythonfmus_binary_with_one_warning(built_fmus, tmp_path, monkeypatch):
    """Catches a build that fails, or warns once per FMU, when no C compiler is there to build the wrapper."""
    import shutil
    import warnings

    import fmus.export.wrapper as wrapper

    fmu = tmp_path / "Trajectory.fmu"
    shutil.copy2(built_fmus["Trajectory"], fmu)
    with zipfile.ZipFile(fmu) as z:   # pythonfmu's binary in place of ours
        items = {i.filename: z.read(i.filename) for i in z.infolist()}
    import pythonfmu
    items["binaries/linux64/Trajectory.so"] = (Path(pythonfmu.__file__).parent / "resources" / "binaries" / "linux64"
                                               / "libpythonfmu-export.so").read_bytes()
    with zipfile.ZipFile(fmu, "w") as z:
        for name, data in items.items():
            z.writestr(name, data)
    monkeypatch.setattr(wrapper, "compiler", lambda: None)
    monkeypatch.setattr(wrapper, "_warned", False)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert not wrapper.install_wrapper(fmu) and not wrapper.install_wrapper(fmu)
    assert len(caught) == 1 and "no C compiler" in str(caught[0].message)
    assert not has_wrapper(fmu)
    monkeypatch.undo()
    assert wrapper.install_wrapper(fmu) and has_wrapper(fmu)


def test_the_wrapper_compiles_without_a_warning(tmp_path):
    """-Wall -Wextra -Werror on the wrapper's source (the build itself does not use -Werror, so
    that a newer compiler's new warning never stops a user's build): an unused variable, a
    signed/unsigned comparison or a missing prototype introduced in the C fails here."""
    import sysconfig

    from fmus.export.wrapper import CFLAGS, SOURCE, compiler

    cc = compiler()
    if cc is None:
        pytest.skip("no C compiler")
    run = subprocess.run([cc, *CFLAGS, "-Wall", "-Wextra", "-Werror", f"-I{sysconfig.get_paths()['include']}",
                          str(SOURCE), "-o", str(tmp_path / "w.so")], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
