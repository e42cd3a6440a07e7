"""libcosim's time unit is the nanosecond: ``fmus.libcosim_runner._experiment`` turns a step
size into whole nanoseconds and refuses, by value, one that is not a whole number of them
(the package's own experiment is stubbed: nothing is run)."""
from __future__ import annotations

import pytest

from fmus import libcosim_runner


@pytest.fixture
def experiment(monkeypatch):
    monkeypatch.setattr(libcosim_runner, "read_ssp_experiment", lambda path: (0.0, 1.0, 1e-3))
    return lambda stop, step: libcosim_runner._experiment("package.ssp", None, stop, step)


def test_a_step_of_whole_nanoseconds_is_taken_as_their_count(experiment):
    """Catches a step size converted to nanoseconds by truncation (3e-9 s as 2 ns), the float rounding of a
    whole number refused (a tolerance not relative to the step), or the package's own
    experiment ignored."""
    assert experiment(2.0, 2e-3) == (2.0, 2e-3, 2_000_000)
    assert experiment(None, None) == (1.0, 1e-3, 1_000_000)          # the package's own experiment
    assert experiment(1.0, 3e-9) == (1.0, 3e-9, 3)
    noisy = 0.1 * 3e-3                                                 # 3.0000000000000003e-04
    assert noisy != 3e-4 and experiment(1.0, noisy) == (1.0, noisy, 300_000)
    off = 0.1 + 0.2                           # 0.30000000000000004 s: 300000000.00000006 ns, 6e-8 ns off
    assert off * 1e9 != 300_000_000 and experiment(1.0, off) == (1.0, off, 300_000_000)


@pytest.mark.parametrize("step", [1.5e-9, 2.5e-9, 0.4e-9, 300000.4e-9])
def test_a_step_that_is_no_whole_number_of_nanoseconds_is_refused_naming_it(experiment, step):
    """Catches a fraction of a nanosecond rounded away: 0.4 ns off 300 us is 1.3e-6 of the step,
    over the 1e-6 the float rounding of a whole number stays far below (the test beside it)."""
    with pytest.raises(ValueError) as refused:
        experiment(1.0, step)
    assert str(refused.value) == f"step_size = {step!r} s is no whole number of nanoseconds (libcosim's time unit)"


def _ssd(step=None):
    """A SystemStructure.ssd element, with libcosim's annotation of ``step`` if given."""
    from fmus.ssp.libcosim import NS, _set_annotation
    import xml.etree.ElementTree as ET

    ssd = ET.Element(f"{{{NS['ssd']}}}SystemStructureDescription")
    if step is not None:
        _set_annotation(ssd, step, None)
    return ssd


@pytest.mark.parametrize("package, ssd_step, given, expected", [
    ((0.0, 2.0, None), 5e-4, (None, None), (2.0, 5e-4, 500_000)),       # the step of libcosim's annotation
    ((0.0, 2.0, 1e-3), 5e-4, (None, None), (2.0, 1e-3, 1_000_000)),     # the package's own step first
    ((0.0, None, None), 5e-4, (3.0, None), (3.0, 5e-4, 500_000)),       # a stop time given, none in the package
    ((None, None, None), None, (0.5, 2e-3), (0.5, 2e-3, 2_000_000)),    # both given
])
def test_what_is_not_given_is_the_packages_own_then_libcosims_annotation(monkeypatch, package, ssd_step, given,
                                                                        expected):
    """Catches the order of the fallbacks reversed (the annotation before the package's own
    step, the package's before what is given) or one of them dropped."""
    monkeypatch.setattr(libcosim_runner, "read_ssp_experiment", lambda path: package)
    assert libcosim_runner._experiment("package.ssp", _ssd(ssd_step), *given) == expected


@pytest.mark.parametrize("package, ssd_step, given, message", [
    ((0.0, None, 1e-3), None, (None, None), "package.ssp: give stop_time and step_size (the package does not)"),
    ((0.0, 1.0, None), None, (None, None), "package.ssp: give stop_time and step_size (the package does not)"),
    ((0.0, 1.0, 1e-3), None, (None, 0.0), "step_size = 0.0 must be > 0"),
    ((0.0, 1.0, 1e-3), None, (None, -1e-3), "step_size = -0.001 must be > 0"),
    ((0.0, 1.0, 1e-3), None, (None, float("nan")), "step_size = nan must be > 0"),
])
def test_a_missing_stop_or_step_and_a_step_not_above_zero_are_refused_naming_them(monkeypatch, package, ssd_step,
                                                                                 given, message):
    """Catches a package without its stop time or step run anyway, a step <= 0 (or NaN)
    taken, and the messages not naming the package or the value."""
    monkeypatch.setattr(libcosim_runner, "read_ssp_experiment", lambda path: package)
    with pytest.raises(ValueError) as refused:
        libcosim_runner._experiment("package.ssp", _ssd(ssd_step), *given)
    assert str(refused.value) == message


def test_an_isolated_run_hands_every_option_to_the_child_and_back(monkeypatch, tmp_path):
    """Catches an option of ``simulate_ssp_libcosim`` (the log level, the worker threads, the
    stop time or step) dropped on the way to the child process of ``isolated=True``, or the
    child's result not the run the options ask for."""
    import pickle
    import sys
    from fmus.ssp import libcosim

    options = dict(stop_time=0.5, step_size=2e-3, log_level="error", worker_threads=3)
    handed = []
    monkeypatch.setattr(libcosim, "_isolated", lambda path, signals, **kwargs: handed.append((path, signals, kwargs)))
    libcosim.simulate_ssp_libcosim("p.ssp", ["a.y"], isolated=True, **options)
    assert handed == [("p.ssp", ["a.y"], options)]
    # the child: what the parent pickled, run in process (here recorded), its outcome written back
    ran = []
    monkeypatch.setattr(libcosim, "simulate_ssp_libcosim", lambda path, signals, **kwargs: ran.append(kwargs) or "run")
    args, result = tmp_path / "args.pickle", tmp_path / "result.pickle"
    args.write_bytes(pickle.dumps(("p.ssp", ["a.y"], options)))
    monkeypatch.setattr(sys, "argv", ["-c", str(args), str(result)])
    libcosim._child()
    assert ran == [options] and pickle.loads(result.read_bytes()) == "run"
