"""DCMotorDrive's ``internal_observer`` (issue 26.3): the drive closes its current loop on
its own estimate.  Its run must be the loop our master closes between two instances,
``DCMotorDrive`` (input ``i_hat``) and ``CurrentObserver`` fed the drive's applied voltage
and the same speed (drive.step -> observer.step -> next drive.step), step for step, also at
sub-steps with a sample phase; and its parameters are refused by name.
"""
from __future__ import annotations

import math

import pytest

from fmus.cosim.backends import CoSimulationError, InProcessInstance

H_SUBSTEPS = 4
STEPS = 60


def _instance(model, name, inputs, outputs, parameters):
    inst = InProcessInstance(model, name)
    inst.bind([inst.variables[n] for n in inputs], [inst.variables[n] for n in outputs])
    inst.initialize(parameters, 0.0)
    return inst


def _i_ref(t):
    return 0.8 * math.sin(40.0 * t) + 0.3


def _omega(t):
    return 12.0 * math.cos(25.0 * t)


#: (observer kind, start state): the dynamic observer integrates over the step (its length
#: matters), a start off zero is the estimate's and the drive's.
KINDS = [("static", {}), ("dynamic", {}), ("dynamic", {"i0": 0.35, "omega0": -4.0})]


@pytest.mark.parametrize("kind, start", KINDS, ids=["static", "dynamic", "dynamic-offset"])
@pytest.mark.parametrize("substeps, phase", [(1, 0), (H_SUBSTEPS, 0), (H_SUBSTEPS, 2)])
@pytest.mark.parametrize("preset", ["motor1", "motor2"])
def test_the_internal_observer_is_the_two_instance_loop(preset, substeps, phase, kind, start):
    """Catches an internal observer that differs from the drive and observer FMUs wired together
    (its kind, the step length it integrates over, its start state)."""
    h = 1e-3 / substeps
    common = {"preset": preset, "mode": "current", "torque_output": "mean", "sample_phase": phase, **start}
    inner = _instance("DCMotorDrive", "inner", ["i_ref", "omega"], ["tau", "v", "i"],
                      {**common, "internal_observer": True, "observer_kind": kind})
    drive = _instance("DCMotorDrive", "drive", ["i_ref", "omega", "i_hat"], ["tau", "v", "i"], common)
    observer = _instance("CurrentObserver", "obs", ["v", "omega"], ["i_hat"],
                         {"preset": preset, "sample_phase": phase, "kind": kind, **start})
    try:
        t, voltages = 0.0, set()
        for _ in range(STEPS):
            # Our master's order: the observer (sampled output) steps first, on the voltage
            # the drive applied over the step just taken and the speed now; then the drive.
            observer.set_inputs([drive.get_outputs()[1], _omega(t)])
            observer.do_step(t, h)
            drive.set_inputs([_i_ref(t), _omega(t), observer.get_outputs()[0]])
            drive.do_step(t, h)
            inner.set_inputs([_i_ref(t), _omega(t)])
            inner.do_step(t, h)
            assert inner.get_outputs() == pytest.approx(drive.get_outputs(), rel=1e-12, abs=1e-15), t
            voltages.add(round(drive.get_outputs()[1], 12))
            t += h
        assert len(voltages) > STEPS // (2 * substeps)   # the controller acted: the voltage moved
    finally:
        for inst in (inner, drive, observer):
            inst.close()


@pytest.mark.parametrize("parameters, names", [
    ({"internal_observer": True, "mode": "voltage"}, "internal_observer"),
    ({"internal_observer": True, "observer_kind": "clairvoyant"}, "observer_kind"),
])
def test_bad_internal_observer_settings_are_refused_by_name(parameters, names):
    """Catches a drive accepting internal_observer with settings it cannot honour."""
    inst = _instance("DCMotorDrive", "d", ["i_ref", "omega"], ["tau"], {"preset": "motor1", **parameters})
    try:
        with pytest.raises(CoSimulationError, match=f"initialisation refused: .*{names}"):
            inst.do_step(0.0, 1e-3)
    finally:
        inst.close()
