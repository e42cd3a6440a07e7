"""The compiled adapter of the actuated plant (``ActuatedFiveBarPlantAdapter.refused``,
fmus/cosim/compiled_adapters.py) makes a refused step's refusal from the trial state the kernel
left in the plant's scratch: the plant's 14 words and the two armature currents, no more, read
back in the refusal's words exactly as the plant's own check names them."""
from __future__ import annotations

import math

import numpy as np

import kernels
from fmus.cosim.compiled_adapters import ActuatedFiveBarPlantAdapter
from plant import fast5r
from tests.fmus.slave.test_extremes import make_slave

H = 1e-3


def test_a_non_finite_current_is_refused_naming_the_two_currents_of_the_trial_state():
    """Catches the trial state read from another buffer or not cut at the state's length (the
    scratch's other words reported as currents)."""
    slave = make_slave("ActuatedFiveBarPlant")
    adapter = ActuatedFiveBarPlantAdapter("plant", slave, H)
    adapter.x = np.zeros(len(adapter.inputs) + len(adapter.outputs))
    scratch = adapter._context.buffers[0].buffers[-1]
    assert scratch.size > adapter.state.size
    scratch[:] = 7.0                                     # words beyond the trial state: never read
    scratch[:adapter.state.size] = adapter.state
    scratch[fast5r.PLANT_STATES] = math.nan
    scratch[fast5r.PLANT_STATES + 1] = 0.25
    refusal = kernels.Refusal(code=fast5r.NONFINITE_STATE, index=fast5r.PLANT_STATES, value=math.nan)
    exc = adapter.refused(refusal, 0.0)
    assert str(exc).startswith("armature currents [nan, 0.25] after the step from t = 0 s ("), str(exc)
    assert exc.record()["variable"] == "i1"


def test_a_singular_pose_is_refused_at_the_trial_states_position_after_the_step():
    """The 5R plant's adapter (``FiveBarPlantAdapter.refused``): a step the kernel declined at a
    singular pose names the pose of the trial state in the scratch (x, y: its words 0 and 1)
    and the step's end time.  Catches the trial read from another buffer or another slice."""
    from fmus.cosim.compiled_adapters import FiveBarPlantAdapter

    slave = make_slave("FiveBarPlant")
    adapter = FiveBarPlantAdapter("plant", slave, H)
    adapter.x = np.zeros(len(adapter.inputs) + len(adapter.outputs))
    scratch = adapter._context.buffers[-1]
    scratch[:] = 7.0
    scratch[:adapter.state.size] = adapter.state
    scratch[:2] = (0.0125, 0.1375)
    refusal = kernels.Refusal(code=fast5r.SINGULAR, index=2, value=1e-9)
    exc = adapter.refused(refusal, 0.5)
    assert "singular pose reached at t = 0.501 s:" in str(exc) and "at x = 0.0125 m, y = 0.1375 m" in str(exc), str(exc)
