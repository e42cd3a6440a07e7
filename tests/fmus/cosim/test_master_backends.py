"""The master's two back ends (fmus/cosim/backends.py) are one interface: an FMU through fmpy
(``_FmuInstance``) and the same slave in process (``InProcessInstance``), given the same
calls, give the same values bit for bit and the same refusal, whatever the variables' types
and their order (the FMU side moves them in one typed array per type, :class:`_Batch`)."""
from __future__ import annotations

import math

import pytest

from fmus.cosim.backends import CoSimulationError, InProcessInstance, _FmuInstance

MODEL = "WheeledPendulum"
#: A parameter of each FMI type, none at its default: a pendulum released at 0.3 rad falls.
PARAMETERS = {"psi0": 0.3, "dtheta0": -0.5, "substeps": 7, "yaw": False, "model": "seed", "encoder_counts": 1000}
#: Outputs of three types in an order that is not the value references' (Boolean first, Reals
#: around the Integer-free middle, the last Real declared first).
OUTPUTS = ("fallen", "psi", "energy", "enc_l", "theta", "fallen", "dpsi")
INPUTS = ("tau_r", "tau_d", "tau_l")


@pytest.fixture(scope="module")
def wheeled_fmu(tmp_path_factory):
    from fmus.export.build import build_fmu

    return build_fmu(MODEL, tmp_path_factory.mktemp("backends"))


def _pair(path, parameters=PARAMETERS, outputs=OUTPUTS):
    pair = (_FmuInstance(path, "w"), InProcessInstance(MODEL, "w"))
    for instance in pair:
        variables = instance.variables
        instance.bind([variables[n] for n in INPUTS], [variables[n] for n in outputs])
        instance.initialize(parameters, 0.0)
    return pair


def _same(a, b):
    """Equal values of equal types (a Boolean read back as a bool, not 1.0)."""
    return [(type(v), v) for v in a] == [(type(v), v) for v in b]


def test_the_fmu_and_in_process_back_ends_step_alike_with_outputs_of_three_types(wheeled_fmu):
    """Catches the FMU back end initialising without its parameters (or failing to), moving a
    type's values to the wrong positions, converting a Boolean or a Real wrongly, or setting the
    inputs to other variables than bound: the in-process slave is the oracle, step by step, up to
    the step where the pendulum falls (fmi2Discard, ``fallen`` True) with the same refusal."""
    fmu, inproc = _pair(wheeled_fmu)
    assert _same(fmu.get_outputs(), inproc.get_outputs())
    assert inproc.get_outputs()[1] == 0.3 and inproc.slave.substeps == 7      # the parameters were applied
    h = 1e-3
    for k in range(400):
        inputs = [0.01 * math.sin(k / 7), -0.02, 0.03 * math.cos(k / 5)]
        errors = []
        for instance in (fmu, inproc):
            instance.set_inputs(inputs)
            try:
                instance.do_step(k * h, h)
            except CoSimulationError as exc:
                errors.append(exc)
        out = fmu.get_outputs()
        assert _same(out, inproc.get_outputs()), k
        if errors:
            break
    assert k > 50 and len(errors) == 2 and out[0] is True and out[5] is True
    assert errors[0].run_error == errors[1].run_error and errors[0].run_error.variable == "psi"
    assert (str(errors[0]), errors[0].time) == (str(errors[1]), errors[1].time) == (str(errors[0]), k * h)
    fmu.close()
    inproc.close()


def test_the_inputs_reach_their_variables_in_order(wheeled_fmu):
    """Catches inputs set to one another's variables: a torque on the left wheel only and one on
    the right wheel only turn the robot opposite ways (the pendulum with yaw)."""
    yawing = {**PARAMETERS, "yaw": True, "psi0": 0.0, "model": "exact"}
    turns = []
    for inputs in ([0.0, 0.0, 0.05], [0.05, 0.0, 0.0]):           # tau_l, then tau_r
        fmu, inproc = _pair(wheeled_fmu, yawing, ("phi", "fallen"))
        for k in range(50):
            for instance in (fmu, inproc):
                instance.set_inputs(inputs)
                instance.do_step(k * 1e-3, 1e-3)
        assert _same(fmu.get_outputs(), inproc.get_outputs())
        turns.append(fmu.get_outputs()[0])
        fmu.close()
    assert turns[0] * turns[1] < 0 and min(map(abs, turns)) > 1e-6


def test_a_state_taken_and_serialised_steps_on_alike(wheeled_fmu):
    """Catches a back end's state calls that restore another state or lose one through its bytes,
    and the FMU's one-call path for Real outputs in order (every parcosim FMU's) reading other
    values than the in-process slave's."""
    fmu, inproc = _pair(wheeled_fmu, outputs=("x", "psi", "energy", "dtheta"))
    assert fmu._outputs.plain and fmu._inputs.plain
    for k in range(20):
        for instance in (fmu, inproc):
            instance.set_inputs([0.01, 0.0, -0.01])
            instance.do_step(k * 1e-3, 1e-3)
    saved = {}
    for name, instance in (("fmu", fmu), ("inproc", inproc)):
        state = instance.get_state()
        saved[name] = instance.deserialize_state(instance.serialize_state(state))
        instance.free_state(state)
    expected = fmu.get_outputs()
    for k in range(20, 40):
        for instance in (fmu, inproc):
            instance.do_step(k * 1e-3, 1e-3)
    assert fmu.get_outputs() != expected
    for name, instance in (("fmu", fmu), ("inproc", inproc)):
        instance.set_state(saved[name])
        assert _same(instance.get_outputs(), expected), name
        instance.do_step(20e-3, 1e-3)
    assert _same(fmu.get_outputs(), inproc.get_outputs())
    fmu.close()
    inproc.close()


def test_a_process_leaves_no_unzipped_fmu_behind(wheeled_fmu, tmp_path):
    """Catches the FMU back end leaving its unzipped copy of every FMU in the temp folder when the
    process exits (2 MB per FMU and process: a sweep or a test suite filled the disk), or
    unzipping one FMU again for each instance: a fresh process with its own temp folder makes
    two instances of one FMU, finds one unzipped folder while they live, and none after exit."""
    import os
    import subprocess
    import sys

    scratch = tmp_path / "tmp"
    scratch.mkdir()
    code = ("import os, sys; from fmus.cosim.backends import _FmuInstance; "
            "a, b = _FmuInstance(sys.argv[1], 'a'), _FmuInstance(sys.argv[1], 'b'); "
            "print(len(os.listdir(sys.argv[2])))")
    done = subprocess.run([sys.executable, "-c", code, str(wheeled_fmu), str(scratch)],
                          env={**os.environ, "TMPDIR": str(scratch)}, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["1"]
    assert os.listdir(scratch) == []
