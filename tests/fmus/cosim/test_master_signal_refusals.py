"""The master's refusals of a system's signals before anything runs (fmus/cosim/master.py
``_check_signals``, fmus/cosim/stepper.py's plan), each message read whole: the signal, what it
is and what was expected (issue 31: these messages were only ever matched by a word or two)."""
from __future__ import annotations

import re
from dataclasses import replace

import numpy as np
import pytest

from fmus.cosim.master import simulate
from fmus.cosim.system import Component, Connection, System


def _plant(record=("plant.x",), connections=(), **parameters):
    """The five-bar plant alone (inputs tau1, tau2; outputs x, y, ...; String output ``error``)."""
    return System((Component("plant", "FiveBarPlant", {"preset": "bench", **parameters}),), connections, record,
                  stop_time=0.01)


@pytest.mark.parametrize("system, message", [
    (_plant(connections=(Connection("plant.tau2", "plant.tau1"),)), "plant.tau2 is a input, expected output"),
    (_plant(connections=(Connection("plant.x", "plant.y"),)), "plant.y is a output, expected input"),
    (_plant(record=("plant.x0",)), "plant.x0 is a parameter, expected output or input or local"),
    (_plant(record=("plant.error",)),
     "plant.error is String; only Real, Integer, Boolean signals can be connected or recorded"),
    (_plant(x=1.0), "component plant: FiveBarPlant has no parameter 'x'"),
    (_plant(record=("plant.tau1",)), "recorded signals must be outputs or connected inputs: ['plant.tau1']"),
])
def test_each_misused_signal_is_refused_naming_it_what_it_is_and_what_was_expected(system, message):
    """A connection from an input or into an output, a parameter or a String recorded, an output
    given as a parameter, an input recorded that nothing feeds: each refused with its whole
    message.  Catches a causality or type check dropped or widened, or a message naming
    another signal."""
    with pytest.raises(ValueError, match=rf"^{re.escape(message)}$"):
        simulate(system)


def test_an_input_given_as_a_parameter_is_accepted():
    """An input may be set as a parameter (its value before any connection), unlike an output (above).
    Catches the accepted causalities of a parameter swapped or widened."""
    assert simulate(replace(_plant(tau1=0.0, tau2=0.0), stop_time=0.002)).error is None


def test_a_connected_input_can_be_recorded_as_the_refusal_message_says():
    """"recorded signals must be outputs or connected inputs": so a connected input is recorded,
    one value a row like its source."""
    system = System((Component("drive1", "DCMotorDrive", {"preset": "motor1", "mode": "voltage", "v_ref": 3.0}),
                     Component("plant", "FiveBarPlant", {"preset": "bench", "x0": -0.002, "y0": 0.108})),
                    (Connection("drive1.tau", "plant.tau1"),), ("plant.tau1", "drive1.tau"), stop_time=0.004)
    result = simulate(system)
    assert result.error is None and len(result["plant.tau1"]) == len(result.time) == 5
    assert np.array_equal(result["plant.tau1"], result["drive1.tau"]) and np.any(result["drive1.tau"][1:] != 0.0)
