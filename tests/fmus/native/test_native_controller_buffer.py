"""The native position controller's law buffer is its pythonfmu twin's, word for word.

The native adapter builds ``pc_law_params`` from the set-up data fmus/native/models.py
writes (the strategies' rows, the presets' geometry, kt) and keeps it, after the law's
state, as the first words of its data (``controller`` in
fmus/native/adapters/pcn_positioncontroller.c); the twin's slave keeps the same buffer
(``controller.law.pack``).  The outputs alone cannot tell some of these words apart (an
adaptive gain with rates 0 leaves k as it is), the buffer can: a strategy row's flag, gain
or law word written wrong in the set-up data.
"""
from __future__ import annotations

import numpy as np
import pytest

from controller import law
from controller.strategies import ALL_STRATEGY_NAMES
from tests.support.fmu_calls import Driver

pytestmark = [pytest.mark.fmu]

#: Words of the law's buffer: its state, then its parameters.
WORDS = law.STATE_SIZE + law.PARAMS_SIZE


def twin_buffer(tmp_path, parameters: dict) -> np.ndarray:
    """The buffer of the pythonfmu slave initialised at t = 0 with ``parameters``."""
    from fmus.slaves.parcosim_positioncontroller import PositionController

    slave = PositionController(instance_name="twin", resources=str(tmp_path))
    for name, value in parameters.items():
        setattr(slave, name, value)
    slave.setup_experiment(0.0)
    slave.enter_initialization_mode()
    slave.exit_initialization_mode()
    assert slave.controller is not None, "the twin refused its set-up"
    return slave.controller._buf.copy()


def native_buffer(native, parameters: dict) -> np.ndarray:
    """The first :data:`WORDS` words of the native FMU's data after initialisation."""
    from fmus.native import state_bytes

    native.fmu.reset()
    native.run([("set", parameters), ("setup", 0.0), ("enter",), ("exit",)])
    return state_bytes.data_words(native.fmu.serializeFMUstate(native.fmu.getFMUstate()))[:WORDS]


@pytest.mark.parametrize("trajectory", ["circle", "hold"])
def test_native_controller_law_buffer_equals_the_twins_for_every_strategy(trajectory, native_fmus, tmp_path):
    """Every strategy (model = exact: no table to build) on a table trajectory and on one
    that uses the circle's: the native buffer equals the twin's exactly, so the set-up data
    of fmus/native/models.py carries each strategy's words as controller.strategies gives
    them (the adaptive flag of a constant-gain strategy 0, its rates 0, space, law, gains)."""
    native = Driver(native_fmus["PositionController"])
    try:
        for name in ALL_STRATEGY_NAMES:
            parameters = {"strategy": name, "trajectory": trajectory, "model": "exact"}
            twin = twin_buffer(tmp_path, parameters)
            assert twin[law.BUF["adaptive"]] == 0.0     # the thesis' and seed 001's strategies: constant k
            np.testing.assert_array_equal(native_buffer(native, parameters), twin, err_msg=name)
    finally:
        native.close()


def test_native_controller_law_buffer_takes_the_adaptive_rates_as_the_twin(native_fmus, tmp_path):
    """gamma1 > 0 makes the gain adaptive with (gamma1, gamma2) in both, word for word."""
    native = Driver(native_fmus["PositionController"])
    try:
        parameters = {"strategy": "TCMDx", "model": "exact", "gamma1": 40.0, "gamma2": 0.0}
        twin = twin_buffer(tmp_path, parameters)
        assert twin[law.BUF["adaptive"]] == 1.0 and list(twin[law.BUF["gamma"]]) == [40.0, 0.0]
        np.testing.assert_array_equal(native_buffer(native, parameters), twin)
    finally:
        native.close()
