"""The C kernel's step (plant.fast5r.FastKernel.step) and the voltages it holds: one voltage per
armature current at the end of z, none for the bare plant, against the analytic current of
an R-L circuit at rest."""
from __future__ import annotations

import math

import numpy as np
import pytest

from plant import PlantSimulator, fast5r, get_preset

START = (-0.002, 0.108)      # the bench circle's start, at rest
R, L = 2.0, 1e-3             # the motor row's armature [ohm, H]
DT = 1e-5                    # 1 % of L / R: the joint barely moves, the current follows the circuit


def _motor_row(joint: int) -> np.ndarray:
    """One ``pc_fivebar_motor`` row on ``joint`` (0: q1, 1: q2) with the armature (R, L)."""
    row = np.zeros(fast5r.MOTOR_COLUMNS)
    for name, value in (("joint", joint), ("R", R), ("L", L), ("kt", 0.05), ("ke", 0.05), ("omega_eps", 1e-3)):
        row[fast5r.MOTOR[name]] = value
    return row


def _rest_state():
    return PlantSimulator(get_preset("bench"), *START).y.copy()


def test_a_bare_plant_step_reads_no_voltage():
    """Without currents in z there is no motor to drive: whatever voltages the call carries, the
    trial state is the one without any, and the kernel's held voltages stay as they were.
    Catches a step that copies voltages for a z with no currents."""
    kernel = fast5r.FastKernel(get_preset("bench"))
    y = _rest_state()
    assert y.size == fast5r.PLANT_STATES
    assert kernel.step(y, 0.01, -0.02, DT) == fast5r.OK
    bare = kernel.scratch[:y.size].copy()
    kernel.voltages[:] = (7.0, -5.0)
    assert kernel.step(y, 0.01, -0.02, DT, voltages=np.array([3.0, -2.0])) == fast5r.OK
    assert np.array_equal(kernel.scratch[:y.size], bare)
    assert kernel.voltages.tolist() == [7.0, -5.0]


@pytest.mark.parametrize("voltages", [(3.0,), (3.0, -1.5)], ids=["one_drive", "two_drives"])
def test_each_current_of_a_step_follows_its_own_voltage(voltages):
    """From rest with zero currents, each current after DT is the R-L circuit's
    V / R (1 - exp(-R DT / L)) for its own voltage (the back-EMF of a joint that barely moved
    is far below the tolerance), and the kernel holds exactly the voltages given.  Catches a
    voltage copied to the wrong current, one voltage too few, or none."""
    kernel = fast5r.FastKernel(get_preset("bench"))
    motors = np.array([_motor_row(j) for j in range(len(voltages))])
    z = np.concatenate([_rest_state(), np.zeros(len(voltages))])
    assert kernel.step(z, 0.0, 0.0, DT, motors, np.array(voltages)) == fast5r.OK
    assert kernel.voltages[:len(voltages)].tolist() == list(voltages)
    currents = kernel.scratch[fast5r.PLANT_STATES:z.size]
    expected = [v / R * (1.0 - math.exp(-R * DT / L)) for v in voltages]
    assert currents == pytest.approx(expected, rel=1e-6)
