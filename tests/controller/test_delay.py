"""The one-sample computation delay (Fidelity.delay_steps, PositionController ``delay_steps``):
the commands reach the outputs n samples late in every mode, and 0 changes nothing."""
from dataclasses import replace

import numpy as np
import pytest

from controller.position import PositionController as InProcess
from controller.strategies import get_strategy
from fmus.cosim.master import simulate
from plant import get_preset
from scenarios.scenes.thesis import Fidelity, bench
from tests.support.fmi_support import FmuInstance
from tests.fmus.slaves.test_fmu_controller import SMALL_GRID, controller_inputs

pytestmark = [pytest.mark.slow]

NAMES = ("q1", "q2", "dq1", "dq2", "ddq1", "ddq2", "x_d", "y_d", "dx_d", "dy_d", "ddx_d", "ddy_d")


@pytest.mark.parametrize("delay", [1, 2])
def test_controller_fmu_applies_the_law_delay_samples_late(built_fmus, delay):
    """An independent in-process law fed the same samples: the FMU's commands at sample k are
    the law's at k - delay (zero before), its errors e1, e2 the present ones."""
    fmu = FmuInstance(built_fmus["PositionController"], dict(SMALL_GRID, strategy="TCMDx", delay_steps=delay))
    law = InProcess(get_preset("bench"), get_strategy("TCMDx"), grid_step=0.01, extent=(-0.02, 0.04, 0.12, 0.18),
                    cache=False)
    computed = []
    for k in range(12):
        meas, ref = controller_inputs(k)
        fmu.step(1e-3, **dict(zip(NAMES, meas + ref)))
        out = law.step_with_errors(k * 1e-3, *meas, *ref, 1e-3)
        computed.append(list(out[:4]))
        expected = computed[k - delay] if k >= delay else [0.0] * 4
        assert [fmu.get(n) for n in ("tau1", "tau2", "i_ref1", "i_ref2")] == expected, k
        assert [fmu.get(n) for n in ("e1", "e2")] == list(out[4:]), k
    fmu.close()


def test_controller_refuses_a_bad_delay(built_fmus):
    """Catches a PositionController FMU accepting a negative delay_steps."""
    fmu = FmuInstance(built_fmus["PositionController"], {"strategy": "PDx", "delay_steps": -1})
    meas, ref = controller_inputs(0)
    assert "parameter delay_steps = -1 must be an integer in [0, 100]" in fmu.refused_step(
        1e-3, **dict(zip(NAMES, meas + ref)))
    fmu.close()


def _short(fidelity, stop=0.6):
    system = bench("TCMDx", "circle", fidelity=fidelity).system
    return replace(system, stop_time=stop)


@pytest.mark.parametrize("delay", [1, 3])
def test_delayed_bench_runs_the_same_rows_compiled_and_in_process(delay):
    """Catches a delay that the compiled loop applies differently from in process, or not at all."""
    delayed = _short(Fidelity(delay_steps=delay))
    fast, slow = simulate(delayed, mode="compiled"), simulate(delayed, mode="inprocess")
    assert fast.mode == "compiled" and fast.extra["python_steps"] == 0
    for name in slow.signals:
        assert np.array_equal(fast[name], slow[name]), name
    # the delay reached the loop: the drive's current reference lags the undelayed run's
    plain = simulate(_short(Fidelity()), mode="compiled")
    assert not np.array_equal(plain["drive1.i"], fast["drive1.i"])


def test_delayed_bench_runs_the_same_rows_as_fmus(tmp_path):
    """Catches a delay that the FMU applies differently from the in-process controller."""
    delayed = _short(Fidelity(delay_steps=1), stop=0.2)
    fmu, slow = simulate(delayed, mode="fmu", fmu_dir=tmp_path), simulate(delayed, mode="inprocess")
    assert fmu.error is None
    for name in slow.signals:
        assert np.array_equal(fmu[name], slow[name]), name


def test_no_delay_is_the_bench_scene_itself():
    """Fidelity(delay_steps=0) adds no parameter: the scene is the default bench scene."""
    assert bench("PDq", "triangle", fidelity=Fidelity(delay_steps=0)) == bench("PDq", "triangle")
