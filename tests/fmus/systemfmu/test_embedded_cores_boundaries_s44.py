"""A component of a system inside an FMU that refuses its initialisation refuses the system's
(fmus/systemfmu/cores.py ``SystemStepper.initialize``; issue 31, training seed 4452 [18]).

An in-process component does not raise when it refuses: it keeps its refusal (``slave.error``)
and the system's initialisation must look at it, raising :class:`InitialisationRefused` in the
component's own words, at the start time, before any step or sample is taken.  No FMU is built.
"""
from __future__ import annotations

from dataclasses import replace

import pytest

from fmus.slave.base import MIN_STEP
from fmus.systemfmu.cores import ChainCore, InitialisationRefused
from scenarios.packaging.chain import package_scene
from scenarios.scenes.catalogue import get_scene


@pytest.fixture(scope="module")
def chain_system():
    return package_scene(get_scene("thesis_sim_circle")).chain


def _with_controller_T(system, T):
    return replace(system, components=tuple(replace(c, parameters={**c.parameters, "T": T}) if c.name == "ctrl"
                                            else c for c in system.components))


def test_a_component_refusing_its_initialisation_refuses_the_systems_in_its_own_words(chain_system):
    """The chain's controller with T = 0 (below its floor MIN_STEP): initialising the chain
    raises, naming the component, t = 0 and the controller's own message, and its record is an
    initialisation refusal of that component."""
    core = ChainCore(_with_controller_T(chain_system, 0.0), "plant")
    with pytest.raises(InitialisationRefused) as refused:
        core.initialize()
    error = refused.value
    assert (error.instance, error.time) == ("ctrl", 0.0)
    assert error.message == f"parameter T = 0.0 s must be >= {MIN_STEP:g} s"
    assert str(error) == f"ctrl: parameter T = 0.0 s must be >= {MIN_STEP:g} s"
    assert (error.run_error.kind.value, error.run_error.instance) == ("initialisation", "ctrl")


def test_a_component_accepting_its_initialisation_lets_the_system_initialise(chain_system):
    """The same chain with the controller's T at the scene's own value initialises (no refusal)."""
    T = next(c.parameters.get("T") for c in chain_system.components if c.name == "ctrl")
    system = chain_system if T is None else _with_controller_T(chain_system, T)
    ChainCore(system, "plant").initialize()
