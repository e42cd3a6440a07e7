"""The right-hand-side evaluations ActuatedPlant.step returns, against a count of its own calls.

The count is what the master charges against a call budget and what the step-length studies
report; each integration path computes it in its own place (the one C call, the C kernel with
projection, the Python RK4 of the general kernel, dopri5), so each is held to the number of
times the ODE's right-hand side was actually called, counted here around
:meth:`plant.actuated.ActuatedPlant.derivative`.
"""
from __future__ import annotations

import numpy as np
import pytest

from motor import Drive, get_motor_preset
from plant import IntegratorSettings, PlantSimulator, get_preset
from plant.actuated import ActuatedPlant

START = (-0.002, 0.108)      # the bench circle's start
STEPS = 2


def _actuated(settings):
    sim = PlantSimulator(get_preset("bench"), *START, settings)
    drives = [(j, Drive(get_motor_preset(f"motor{j}"))) for j in (1, 2)]
    return ActuatedPlant(sim, drives)


def _counted(a):
    """``a`` with its derivative counted: returns the list the calls are appended to."""
    calls, derivative = [], a.derivative

    def counting(z, voltages, external):
        calls.append(1)
        return derivative(z, voltages, external)

    a.derivative = counting
    return calls


def _steps(a, dt=1e-3):
    """The evaluations each of STEPS current-driven steps returned."""
    return [a.step((2.0, -1.5 + 0.5 * k), [d.i for _, d in a.drives], (0.0, 0.0), dt) for k in range(STEPS)]


def test_a_python_integration_returns_the_derivative_calls_it_made(substeps=3):
    """Catches a count that is not the number of right-hand-side calls (4 per RK4 substep
    written as 4 / substeps, a constant, dopri5's count dropped) on the Python paths, at three
    substeps (where 4 / substeps and 4 * substeps differ)."""
    for settings in (IntegratorSettings(kernel="general", substeps=substeps),
                     IntegratorSettings(method="dopri5", rtol=1e-6, atol=1e-9)):
        a = _actuated(settings)
        calls = _counted(a)
        returned = _steps(a)
        assert sum(returned) == len(calls) > 0, settings
        if settings.method == "rk4":
            assert returned == [4 * substeps] * STEPS


@pytest.mark.parametrize("substeps", [1, 3])
def test_the_compiled_steps_return_what_the_python_rk4_calls(substeps):
    """Catches the one-call step (or the C kernel with projection) returning another count
    than the Python RK4 of the same settings makes calls (4 / substeps, substeps, 4), at one
    substep and at three."""
    general = _actuated(IntegratorSettings(kernel="general", substeps=substeps))
    calls = _counted(general)
    _steps(general)
    per_step = len(calls) // STEPS
    assert per_step * STEPS == len(calls)
    for settings in (IntegratorSettings(substeps=substeps), IntegratorSettings(substeps=substeps, project=True)):
        a = _actuated(settings)
        assert a.plant._fast is not None, "the bench preset runs the C kernel by default"
        assert _steps(a) == [per_step] * STEPS, settings


def test_a_dopri5_step_stopped_at_its_work_limit_leaves_plant_and_controllers_as_they_were():
    """dopri5 stopped by ``max_evaluations`` (7: one step's six stages and the first of the
    next, with a tolerance that needs many) raises WorkLimitError after the drives sampled
    their voltages: the plant's state and time and each drive's buffers (current,
    voltage, controller) read back exactly as before, and the full step from there is the
    step of a twin never stopped.  Catches the controllers not put back (or the snapshots
    not taken when a limit is set)."""
    from plant.integrators import WorkLimitError

    settings = IntegratorSettings(method="dopri5", rtol=1e-12, atol=1e-15)
    a, twin = _actuated(settings), _actuated(settings)
    inputs = ((2.0, -1.5), [d.i for _, d in a.drives], (0.0, 0.0), 1e-3)
    y, t = a.plant.y.copy(), a.plant.time
    kept = [d.controller_state() for _, d in a.drives]
    with pytest.raises(WorkLimitError):
        a.step(*inputs, max_evaluations=7)
    assert a.plant.y.tolist() == y.tolist() and a.plant.time == t
    for (_, d), (buf, controller) in zip(a.drives, kept):
        # (a buffer holds NaN where a value is not yet known: equal as NaN)
        assert np.array_equal(d.buf, buf, equal_nan=True)
        assert np.array_equal(d._controller_buf, controller, equal_nan=True)
    a.step(*inputs)
    twin.step(*inputs)
    assert a.plant.y.tolist() == twin.plant.y.tolist()
    for (_, d), (_, e) in zip(a.drives, twin.drives):
        assert np.array_equal(d.buf, e.buf, equal_nan=True)
