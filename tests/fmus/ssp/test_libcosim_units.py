"""Units of fmus/ssp/libcosim.py without running libcosim: the record of a step libcosim refused
(``_refusal``), the annotated copy's destination (``with_libcosim_annotation``) and the split of a
run's time (``simulate_ssp_libcosim``'s ``extra``), its signals' checks and which package it loads, and the
log levels, with libcosimpy's objects and the clock stood in.

``_refusal`` reads each component's String output ``refusal`` through a last-value observer;
the observer here is a stand-in (libcosimpy's hands ``c_char_p`` values: bytes or None; a
``str`` is taken as it is) so that every kind of value is checked, not only those one FMU
happens to produce.
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

pytest.importorskip("libcosimpy")

from libcosimpy.CosimEnums import CosimVariableType  # noqa: E402

from fmus.ssp import libcosim  # noqa: E402
from fmus.status import RunError, RunStatus  # noqa: E402

#: A component's refusal record, as its String output holds it.
RECORD = RunError(RunStatus.REFUSED, "input q1 = nan is not finite", instance="ctrl", time=0.25)


class Observer:
    """A last-value observer whose String values are ``values`` (slave index -> value)."""

    def __init__(self, values, reference=7):
        self.values, self.reference = values, reference

    def last_string_values(self, index, references):
        assert references == [self.reference]
        return [self.values[index]]


def refusal(monkeypatch, values, message="step failed"):
    """``_refusal`` of two components, ``a`` (index 0) and ``ctrl`` (index 1), whose outputs
    ``refusal`` (reference 7) hold ``values``."""
    from libcosimpy import CosimObserver as module

    monkeypatch.setattr(module.CosimObserver, "create_last_value", staticmethod(lambda: Observer(values)))
    string = SimpleNamespace(type=CosimVariableType.STRING.value, reference=7)
    variables = {"a": {"refusal": string}, "ctrl": {"refusal": string}}
    execution = SimpleNamespace(add_observer=lambda observer: True)
    return libcosim._refusal(execution, {"ctrl": 1, "a": 0}, variables, 0.25, message)


@pytest.mark.parametrize("text", [RECORD.to_json(), RECORD.to_json().encode()])
def test_a_components_refusal_text_is_the_record_whether_bytes_or_str(text, monkeypatch):
    """The first component (by index) whose refusal is not empty names the record: its
    message, instance and time, as bytes (libcosimpy) or as str."""
    error = refusal(monkeypatch, {0: None, 1: text})
    assert error.instance == "ctrl" and error.time == 0.25 and "input q1 = nan is not finite" in str(error)
    assert error.kind is RunStatus.REFUSED


@pytest.mark.parametrize("empty", [None, "", b""])
def test_without_a_refusal_text_libcosims_message_is_the_record(empty, monkeypatch):
    """No component says why (None, "" or b""): libcosim's message and the step's time."""
    error = refusal(monkeypatch, {0: empty, 1: empty}, message=" the slave failed \n")
    assert error.instance is None
    assert str(error) == "libcosim stopped at the step from t = 0.25 s: the slave failed"


def minimal_package(path):
    """A package of one SystemStructure.ssd (no default experiment) and one other file."""
    import zipfile

    from fmus.ssp.export import NS

    ssd = (f'<?xml version="1.0" encoding="UTF-8"?>\n<ssd:SystemStructureDescription xmlns:ssd="{NS["ssd"]}" '
           f'xmlns:ssc="{NS["ssc"]}" version="1.0" name="s"><ssd:System name="root"/>'
           '</ssd:SystemStructureDescription>\n')
    with zipfile.ZipFile(path, "w") as zf:
        zf.writestr("SystemStructure.ssd", ssd)
        zf.writestr("resources/a.fmu", b"not really an FMU")
    return path


@pytest.mark.parametrize("name", ["copy.ssp", "copy.SSP", "unpacked"])
def test_the_annotated_copy_is_written_at_out_and_the_package_is_left_as_it_was(name, tmp_path):
    """``out`` (a package for .ssp in any case, else a directory) holds the annotation with the
    given step and threads and every file of the package; the package itself is unchanged."""
    import zipfile

    source = minimal_package(tmp_path / "source.ssp")
    before = source.read_bytes()
    out = libcosim.with_libcosim_annotation(source, tmp_path / name, step=2e-3, worker_threads=3)
    assert out == tmp_path / name and source.read_bytes() == before
    assert libcosim.read_libcosim_step(source) == (None, None)
    if out.is_dir():
        assert (out / "resources" / "a.fmu").read_bytes() == b"not really an FMU"
        with zipfile.ZipFile(tmp_path / "check.ssp", "w") as zf:     # read it back as read_libcosim_step reads
            zf.writestr("SystemStructure.ssd", (out / "SystemStructure.ssd").read_bytes())
        assert libcosim.read_libcosim_step(tmp_path / "check.ssp") == (2e-3, 3)
    else:
        assert zipfile.is_zipfile(out)
        with zipfile.ZipFile(out) as zf:
            assert sorted(zf.namelist()) == ["SystemStructure.ssd", "resources/a.fmu"]
        assert libcosim.read_libcosim_step(out) == (2e-3, 3)


def test_an_annotated_copy_without_a_step_is_refused_when_the_package_gives_none(tmp_path):
    """No step passed and none in the package's default experiment: ValueError naming the package."""
    source = minimal_package(tmp_path / "source.ssp")
    with pytest.raises(ValueError, match="gives no communication step; pass step"):
        libcosim.with_libcosim_annotation(source, tmp_path / "out.ssp")
    assert not (tmp_path / "out.ssp").exists()


class Clock:
    """A stand-in for time.perf_counter that moves only when libcosim works: 10 s to load the
    package, 1 s a step, so each reading says how much work came before it."""

    def __init__(self):
        self.now = 100.0     # not 0: a reading added where one is subtracted shows

    def perf_counter(self):
        return self.now


class Execution:
    """A stand-in CosimExecution of no FMU whose steps all succeed (and advance ``clock``)."""

    def __init__(self, clock):
        self.clock, self.steps = clock, 0

    def slave_infos(self):
        return []

    def add_observer(self, observer):
        return True

    def step(self):
        self.steps += 1
        self.clock.now += 1.0
        return True


@pytest.mark.parametrize("steps", [1, 3])
def test_init_s_is_the_first_step_and_steps_s_the_others(steps, monkeypatch, tmp_path):
    """libcosim initialises the FMUs in the first ``step()``: ``init_s`` is that step, ``steps_s``
    the other steps - 1 (none for a run of one step), ``load_s`` the loading; every step is taken."""
    from libcosimpy import CosimExecution as execution_module, CosimObserver as observer_module

    clock = Clock()
    runs = []

    def load(path):
        clock.now += 10.0
        runs.append(Execution(clock))
        return runs[-1]

    monkeypatch.setattr(libcosim, "_time", clock)
    monkeypatch.setattr(execution_module.CosimExecution, "from_ssp_file", staticmethod(load))
    monkeypatch.setattr(observer_module.CosimObserver, "create_time_series", staticmethod(lambda **kw: object()))
    monkeypatch.setattr(observer_module.CosimObserver, "create_last_value", staticmethod(lambda: object()))
    source = minimal_package(tmp_path / "source.ssp")
    run = libcosim.simulate_ssp_libcosim(source, [], stop_time=steps * 1e-3, step_size=1e-3, isolated=False)
    assert runs[0].steps == steps and run.error is None
    assert (run.extra["load_s"], run.extra["init_s"], run.extra["steps_s"]) == (10.0, 1.0, steps - 1.0)
    assert run.wall_s == 10.0 + steps


def test_each_log_level_is_libcosims_own_warn_and_any_case_included_others_refused(monkeypatch):
    """trace ... fatal set libcosim's level of that name ("warn" is "warning", any letter case);
    another name is refused naming the six."""
    from libcosimpy import CosimLogging

    set_to = []
    monkeypatch.setattr(CosimLogging, "log_output_level", set_to.append)
    for level in libcosim.LOG_LEVELS:
        libcosim.set_libcosim_log_level(level)
    libcosim.set_libcosim_log_level("WARN")
    libcosim.set_libcosim_log_level("Error")
    assert [v.name for v in set_to] == ["TRACE", "DEBUG", "INFO", "WARNING", "ERROR", "FATAL", "WARNING", "ERROR"]
    with pytest.raises(ValueError) as refused:
        libcosim.set_libcosim_log_level("verbose")
    assert str(refused.value) == "log level 'verbose': one of trace, debug, info, warning, error, fatal"
    assert len(set_to) == 8


class Variable:
    def __init__(self, name, kind, reference):
        self.name, self.type, self.reference = name.encode(), kind.value, reference


def _stood_in(monkeypatch, loaded):
    """libcosimpy stood in: one slave ``plant`` (index 4) with a Real ``x`` and a String ``refusal``;
    ``loaded`` gets the path each execution is made from."""
    from libcosimpy import CosimExecution as execution_module, CosimObserver as observer_module

    class Plant(Execution):
        def slave_infos(self):
            return [SimpleNamespace(name=b"plant", index=4)]

        def slave_variables(self, index):
            assert index == 4
            return [Variable("x", CosimVariableType.REAL, 11), Variable("refusal", CosimVariableType.STRING, 12)]

    def load(path):
        loaded.append(path)
        return Plant(Clock())

    monkeypatch.setattr(execution_module.CosimExecution, "from_ssp_file", staticmethod(load))
    monkeypatch.setattr(observer_module.CosimObserver, "create_time_series", staticmethod(lambda **kw: SimpleNamespace(
        start_time_series=lambda slave, reference, kind: None)))
    monkeypatch.setattr(observer_module.CosimObserver, "create_last_value", staticmethod(lambda: object()))
    monkeypatch.setattr(libcosim, "_real_samples", lambda series, slave, reference, count: (
        np.arange(count, dtype=float) * reference, np.arange(count, dtype=np.int64) * 1_000_000))


def test_signals_must_be_real_variables_of_the_packages_slaves(monkeypatch, tmp_path):
    """A signal of no slave or no variable, or one that is not a Real, is refused naming it; a Real
    is recorded from its slave's index and reference."""
    _stood_in(monkeypatch, [])
    source = minimal_package(tmp_path / "source.ssp")
    for signal, says in (("plant.v", "plant.v: no such variable in "), ("motor.x", "motor.x: no such variable in "),
                         ("plant.refusal", "plant.refusal is STRING, not a Real")):
        with pytest.raises(ValueError, match=says):
            libcosim.simulate_ssp_libcosim(source, [signal], stop_time=2e-3, step_size=1e-3, isolated=False)
    run = libcosim.simulate_ssp_libcosim(source, ["plant.x"], stop_time=2e-3, step_size=1e-3, isolated=False)
    assert list(run.signals["plant.x"]) == [0.0, 11.0, 22.0] and list(run.time) == [0.0, 1e-3, 2e-3]


def test_a_package_annotated_with_the_runs_step_and_threads_is_loaded_as_it_is(monkeypatch, tmp_path):
    """libcosim loads the package itself when its OSP annotation gives this step and these
    worker threads, else an annotated copy (another step, other threads, no annotation)."""
    loaded = []
    _stood_in(monkeypatch, loaded)
    bare = minimal_package(tmp_path / "bare.ssp")
    annotated = libcosim.with_libcosim_annotation(bare, tmp_path / "annotated.ssp", step=1e-3, worker_threads=0)
    for path, step, threads in ((annotated, 1e-3, 0), (annotated, 2e-3, 0), (annotated, 1e-3, None), (bare, 1e-3, 0)):
        libcosim.simulate_ssp_libcosim(path, [], stop_time=4e-3, step_size=step, worker_threads=threads,
                                       isolated=False)
    assert loaded[0] == str(annotated)
    assert all(p != str(annotated) and p != str(bare) and p.endswith("package") for p in loaded[1:]), loaded


@pytest.mark.parametrize("fails_at, observed, refusal, expected", [
    (0, False, None, (RunStatus.INITIALISATION, None, 0.0, 0)),   # nothing observed: initialisation failed
    (0, True, None, (RunStatus.REFUSED, None, 0.0, 1)),           # the state after initialisation observed
    (2, True, None, (RunStatus.REFUSED, None, 2e-3, 3)),          # the step from t = 2 ms
    (2, False, None, (RunStatus.REFUSED, None, 2e-3, 0)),         # steps were taken: not initialisation
    (0, False, RECORD.to_json().encode(), (RunStatus.REFUSED, "plant", 0.25, 0)),  # a component said why (its time)
])
def test_a_failed_step_is_the_components_record_or_libcosims_and_initialisation_when_nothing_was_seen(
        fails_at, observed, refusal, expected, monkeypatch, tmp_path):
    """libcosim's step k fails: the run stops there with the rows so far, the error at t = k h; its
    kind is "initialisation" only when libcosim's own message is all there is and not even the
    state after initialisation was observed."""
    from libcosimpy import CosimExecution as execution_module, CosimObserver as observer_module, _internal

    _stood_in(monkeypatch, [])
    real_load = execution_module.CosimExecution.from_ssp_file

    def load(path):
        execution = real_load(path)
        execution.step = lambda: execution.steps != fails_at and not execution.__dict__.update(
            steps=execution.steps + 1)
        return execution

    def samples(series, slave, reference, count):
        n = fails_at + 1 if observed else 0
        if n == 0:
            raise RuntimeError("no samples")
        return np.full(n, 1.5), np.arange(n, dtype=np.int64) * 1_000_000

    monkeypatch.setattr(execution_module.CosimExecution, "from_ssp_file", staticmethod(load))
    monkeypatch.setattr(libcosim, "_real_samples", samples)
    monkeypatch.setattr(_internal, "get_last_error_message", lambda: " model error \n")
    monkeypatch.setattr(observer_module.CosimObserver, "create_last_value",
                        staticmethod(lambda: Observer({4: refusal}, reference=12)))
    run = libcosim.simulate_ssp_libcosim(minimal_package(tmp_path / "p.ssp"), ["plant.x"], stop_time=5e-3,
                                         step_size=1e-3, isolated=False)
    kind, instance, t, rows = expected
    assert (run.error.kind, run.error.instance, run.error.time, len(run.time)) == (kind, instance, t, rows)
    if kind is RunStatus.INITIALISATION:
        assert str(run.error) == "libcosim could not initialise the FMUs: model error"
    elif instance is None:
        assert str(run.error) == f"libcosim stopped at the step from t = {t:.6g} s: model error"
