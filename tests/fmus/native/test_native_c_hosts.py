"""The C hosts of issue 28, item 6, no Python in their process: the plain FMI 2.0 Jacobi host
(``tests/native_host/fmi2_host.c``), Ecos's C library (``ecos_host.c``) and libcosim's C
library (``host.c``) loading one FMU from a package whose OSP annotation sets its worker
threads (``tests/native_host/c_hosts.py``).  Each is checked against an expectation formed
without it: the closed-form Jacobi run of two low-passes, or another host stepping the same
FMU.  Nothing here is timed (benchmarks/native_c_hosts.py measures)."""
from __future__ import annotations

import os

import numpy as np
import pytest

from tests.native_host.c_hosts import (build_ecos_host, build_fmi2_host, one_fmu_package, plain_config,
                                       run_ecos_host, run_fmi2_host, ssp_parts)
from tests.native_host.host import HostUnavailable, build_host, config_text, run_host

pytestmark = [pytest.mark.fmu]

H = 1e-3
TAU_A, TAU_B, U = 0.01, 0.02, 2.0
#: The whole loop's stop in these tests: long enough to leave the start, short for a test.
STOP = 0.5


def _built(build, tmp_path_factory, name):
    try:
        return build(tmp_path_factory.mktemp(name))
    except HostUnavailable as exc:
        pytest.skip(str(exc))


@pytest.fixture(scope="module")
def plain(tmp_path_factory):
    return _built(build_fmi2_host, tmp_path_factory, "plain")


@pytest.fixture(scope="module")
def ecos(tmp_path_factory):
    return _built(build_ecos_host, tmp_path_factory, "ecos")


@pytest.fixture(scope="module")
def libcosim(tmp_path_factory):
    return _built(build_host, tmp_path_factory, "libcosim")


@pytest.fixture(scope="module")
def lowpass(tmp_path_factory):
    """The C low-pass FMU of benchmarks/baseline_fmu (y' = (u - y) / tau, exact per step)."""
    from benchmarks.cold_start import build_baseline

    return build_baseline(tmp_path_factory.mktemp("lowpass"))


def values(run, names) -> np.ndarray:
    return np.array([float(run.report[f"value.{n}"]) for n in names])


def test_the_plain_host_steps_a_lowpass_chain_as_the_closed_form_jacobi_master(plain, lowpass, tmp_path):
    """Two low-passes in series (y' = (u - y) / tau, exact per step) under a Jacobi master: b
    holds over each step the value a had at the step's start.  Catches a Gauss-Seidel
    transfer (b fed a's new value), a connection copied to the wrong input, a wrong step
    count or length, and initial values not set in Initialization Mode."""
    fmu = lowpass
    steps = 250
    config = plain_config(tmp_path / "run", H, steps * H, {"a": fmu, "b": fmu}, [("a.y", "b.u")],
                          outputs=["a.y", "b.y"], reals=[("a.u", U), ("a.tau", TAU_A), ("b.tau", TAU_B)])
    run = run_fmi2_host(plain, tmp_path / "run", config)
    a = b = 0.0
    for _ in range(steps):
        a, b = U + (a - U) * np.exp(-H / TAU_A), a + (b - a) * np.exp(-H / TAU_B)
    assert int(run.report["steps"]) == steps and run.report["threads"] == "1"
    np.testing.assert_allclose(values(run, ["a.1", "b.1"]), [a, b], rtol=1e-12)


def test_the_plain_hosts_profile_times_without_changing_the_run(plain, lowpass, tmp_path):
    """``profile 1`` (each FMU's doSteps and the transfers timed apart) gives the same values
    as the plain run, bit for bit, and a time for every FMU and the transfers.  Catches the
    timed path stepping or transferring otherwise than the plain one."""
    fmus, links = {"a": lowpass, "b": lowpass}, [("a.y", "b.u")]
    reals, outputs = [("a.u", U), ("a.tau", TAU_A), ("b.tau", TAU_B)], ["a.y", "b.y"]
    runs = [run_fmi2_host(plain, tmp_path / str(p), plain_config(tmp_path / str(p), H, 0.1, fmus, links, outputs,
                                                                 profile=p, reals=reals)) for p in (False, True)]
    assert values(runs[0], ["a.1", "b.1"]).tolist() == values(runs[1], ["a.1", "b.1"]).tolist()
    assert {k for k in runs[1].report if k.startswith(("dostep_s.", "transfer_s"))} == \
        {"dostep_s.a", "dostep_s.b", "transfer_s"}
    assert "transfer_s" not in runs[0].report


def test_the_plain_host_refuses_an_input_fed_twice(plain, lowpass, tmp_path):
    """Catches a plan that lets the second connection into one input silently win."""
    fmu = lowpass
    config = plain_config(tmp_path / "run", H, 10 * H, {"a": fmu, "b": fmu, "c": fmu}, [("a.y", "c.u"), ("b.y", "c.u")])
    with pytest.raises(RuntimeError, match="an input is fed by two connections, of: c"):
        run_fmi2_host(plain, tmp_path / "run", config)


@pytest.fixture(scope="module")
def loop_runs(native_loop_fmu, plain, ecos, libcosim, tmp_path_factory):
    """The native ClosedLoop over STOP at 1 ms doSteps in each host: name -> HostRun."""
    work = tmp_path_factory.mktemp("loop_runs")
    zero = one_fmu_package(native_loop_fmu, work / "w0.ssp", H, 0)
    pool = one_fmu_package(native_loop_fmu, work / "pool.ssp", H, None)
    outputs = ["loop.x", "loop.y"]
    runs = {"plain": run_fmi2_host(plain, work / "plain",
                                   plain_config(work / "plain", H, STOP, {"loop": native_loop_fmu}, outputs=outputs)),
            "ecos": run_ecos_host(ecos, zero, H, STOP, values=outputs)}
    for name, ssp in (("libcosim w0", zero), ("libcosim pool", pool)):
        runs[name] = run_host(libcosim, work / name.replace(" ", "_"), config_text(STOP, ssp=ssp, outputs=outputs))
    runs["libcosim added"] = run_host(libcosim, work / "added", config_text(STOP, step=H, outputs=outputs,
                                                                           slaves=[("loop", native_loop_fmu)]))
    return runs


def test_every_c_host_steps_the_native_closed_loop_alike(loop_runs):
    """The same FMU at the same doSteps gives the same x, y at the end in all three C
    libraries, bit for bit.  Catches a host taking a step too many or too few, stepping from
    the wrong communication points, or an SSP wrapper (one_fmu_package) that loses the FMU's
    step: the checked values move by millimetres within a step."""
    plain = loop_runs["plain"]
    expected = [float(v) for k, v in plain.report.items() if k.startswith("value.loop.")]
    assert int(plain.report["steps"]) == round(STOP / H) and len(expected) == 2
    assert values(loop_runs["ecos"], ["loop::x", "loop::y"]).tolist() == expected
    for name in ("libcosim w0", "libcosim pool", "libcosim added"):
        run = loop_runs[name]
        assert float(run.report["simulated_s"]) == pytest.approx(STOP, abs=1e-9), name
        assert [run.columns["loop.x"][-1], run.columns["loop.y"][-1]] == expected, name


def test_numworkerthreads_zero_steps_libcosim_on_the_calling_thread(loop_runs):
    """What docs/native.md tells users to do in libcosim's C host: the package's
    ``numWorkerThreads="0"`` leaves one thread, which does all the stepping; libcosim's
    default (the FMU added with cosim_execution_create, or the annotation without a count)
    starts hardware_concurrency - 1 worker threads.  Catches an annotation libcosim ignores
    (a wrong prefix or attribute name: it would take its default silently)."""
    zero = loop_runs["libcosim w0"]
    assert zero.report["threads"] == "1"
    assert float(zero.report["thread_cpu_s"]) == pytest.approx(float(zero.report["cpu_s"]), rel=0.02, abs=2e-3)
    workers = max((os.cpu_count() or 1) - 1, 0)
    for name in ("libcosim pool", "libcosim added"):
        assert loop_runs[name].report["threads"] == str(1 + workers), name


def test_the_plain_host_runs_a_package_as_libcosim_does(plain, libcosim, lowpass_package, tmp_path):
    """An SSP package of three chained low-passes read by ssp_parts, its Real parameter
    bindings set in Initialization Mode (as libcosim applies them; the C low-pass reads no
    start value from its description), stepped by the plain host equals libcosim's run of the
    package, bit for bit.  Catches connections read from the SSD the wrong way round or
    dropped."""
    from fmus.ssp.export import read_ssp_parameters

    package, signals = lowpass_package
    fmus, links = ssp_parts(package, tmp_path / "parts")
    assert sorted(links) == [("lp0.y", "lp1.u"), ("lp1.y", "lp2.u")]
    reals = [(name, value) for name, value in read_ssp_parameters(package).items() if isinstance(value, float)]
    run = run_fmi2_host(plain, tmp_path / "plain", plain_config(tmp_path / "plain", H, 0.2, fmus, links,
                                                                outputs=signals, reals=reals))
    reference = run_host(libcosim, tmp_path / "libcosim", config_text(0.2, ssp=package, outputs=signals))
    ours = [float(v) for k, v in run.report.items() if k.startswith("value.")]
    assert ours == [reference.columns[s][-1] for s in signals]
    assert len(set(ours)) == len(ours)          # three different values: the chain moved


@pytest.fixture
def lowpass_package(lowpass, tmp_path):
    """Three chained C low-passes with their own time constants, u of the first at 1, as one
    package (``export_ssp``)."""
    from fmus.cosim.system import Component, Connection, System
    from fmus.ssp.export import export_ssp

    names = ["lp0", "lp1", "lp2"]
    components = tuple(Component(n, "LowPass", parameters={"tau": 0.01 * (k + 1), **({"u": 1.0} if k == 0 else {})})
                       for k, n in enumerate(names))
    system = System(components=components, connections=(Connection("lp0.y", "lp1.u"), Connection("lp1.y", "lp2.u")),
                    record=tuple(f"{n}.y" for n in names), stop_time=0.2, step=H)
    return export_ssp(system, tmp_path / "chain.ssp", fmus={"LowPass": lowpass}), [f"{n}.y" for n in names]
