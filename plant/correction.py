"""Bring a model of the plant back in line with what was measured of the real one.

A controller that predicts the plant one sample ahead with a model of it (the sampled
chain of an exported package, :mod:`fmus.systemfmu.cores`) runs that model beside the real
plant; each sample it compares the model's outputs with the measured ones and, where
they disagree, moves the model's state to the nearest state the measurement allows:

* an exact measurement (``q1``, ``q2``, ``dq1``, ``dq2``) is taken as it is (unless the
  model is within :data:`EXACT_TOLERANCE` of it);
* an encoder reading ``q<j>_enc`` = c round(q_j / c) (c one count, as the plant rounds)
  only says q_j lies in [q_enc - c/2, q_enc + c/2): a model angle outside that cell is
  moved just inside it, and its speed by a fraction of that move per step
  (:data:`VELOCITY_GAIN`); one inside is left alone.

The new state keeps the model's unmeasured quantities (the end effector's velocity where
no speed is measured) and closes the loop exactly: the end effector from the actuated
angles by the direct kinematics (002 eq. 7-11, working mode), the thesis coordinates
(7.12) from it, the speeds through J_X dX + J_Theta dTheta = 0 (002 eq. 15) and C (5.56).
"""
from __future__ import annotations

import math

import numpy as np

from . import fivebar
from .parallel import mechanism_state

#: Where in its encoder cell a corrected angle goes: this fraction of a count inside
#: the cell's edge (at the edge itself the reading would flip on rounding noise).
CELL_MARGIN = 0.05
#: A moved angle also moves its speed by this fraction of (the move / the step): a
#: model that leaves its encoder cell is off in speed too, and without a speed correction
#: it leaves the cell again at once (where the speed is not measured).  A moderate
#: observer gain; measured with the drives in the plant on 2 s of three bench scenes with a
#: 0, 40 and 100 g payload the model does not have (docs/ssp.md), RMS error against the
#: master's with the same plant: gain 0: 1.00-1.35x, 0.1: 0.995-1.08x, 0.3: 0.996-1.05x,
#: 1: 0.997-1.03x (twice the corrections).
VELOCITY_GAIN = 0.3
#: An exact measurement this close to the model's value [rad, rad/s] leaves the model
#: alone: masters that compute the step size as a difference of communication points
#: (libcosim, in integer nanoseconds) give the plant steps an ulp off the model's, and
#: its state drifts from the model's by ulps that no physics cares about (a correction
#: every step made libcosim 10 times slower); a model error shows far above it.
EXACT_TOLERANCE = 1e-10
MEASURABLE = ("q1", "q2", "dq1", "dq2", "q1_enc", "q2_enc")


def corrected_state(sim, measured: dict, step: float):
    """The state of ``sim`` (a :class:`plant.PlantSimulator`) made consistent with ``measured``.

    Parameters
    ----------
    sim : PlantSimulator
        The model; its ``y`` = [q (7), dq (7)], ``params`` and ``count`` (one encoder count).
    measured : dict
        Some of :data:`MEASURABLE` -> measured value (world convention, as the plant's
        outputs).
    step : float
        The sample time [s]: an angle moved by d into its encoder cell moves its speed by
        :data:`VELOCITY_GAIN` d / step (unless the speed is measured).

    Returns
    -------
    numpy.ndarray or None
        The corrected [q, dq], or None when the model already agrees with every
        measurement (the state is then left exactly as it is).
    """
    unknown = set(measured) - set(MEASURABLE)
    if unknown:
        raise ValueError(f"cannot correct the plant model with {sorted(unknown)}; measurable: {MEASURABLE}")
    y = sim.y
    angles = list(fivebar.world_angles(y[:7]))
    rates = list(fivebar.world_rates(y[7:]))
    changed = False
    for j in (0, 1):
        exact = measured.get(f"q{j + 1}")
        reading = measured.get(f"q{j + 1}_enc")
        if exact is not None and abs(exact - angles[j]) > EXACT_TOLERANCE:
            angles[j], changed = float(exact), True
        elif exact is None and reading is not None:
            offset = sim.encoder_offsets[j]    # the reading is of angle + offset
            inside = _into_cell(angles[j] + offset, float(reading), sim.count) - offset
            if inside != angles[j]:
                if measured.get(f"dq{j + 1}") is None:
                    rates[j] += VELOCITY_GAIN * (inside - angles[j]) / step
                angles[j], changed = inside, True
        speed = measured.get(f"dq{j + 1}")
        if speed is not None and abs(speed - rates[j]) > EXACT_TOLERANCE:
            rates[j], changed = float(speed), True
    if not changed:
        return None
    return consistent_state(sim, angles, rates)


def _into_cell(angle: float, reading: float, count: float) -> float:
    """``angle`` if it rounds to ``reading``, else the nearest angle just inside its cell."""
    n = round(reading / count)
    if math.floor(angle / count + 0.5) == n:
        return angle
    low, high = (n - 0.5) * count, (n + 0.5) * count
    return low + CELL_MARGIN * count if angle < low else high - CELL_MARGIN * count


def consistent_state(sim, angles, rates) -> np.ndarray:
    """[q, dq] of the closed loop with actuated angles ``angles`` and speeds ``rates``
    (world convention), in the working mode."""
    x, y = fivebar.direct_kinematics(sim.params, angles[0], angles[1])
    JX, JT = fivebar.jacobians(sim.params, x, y, angles[0], angles[1])
    velocity = -np.linalg.solve(JX, JT @ np.asarray(rates, dtype=float))
    q = fivebar.thesis_coordinates(sim.params, x, y)
    C = mechanism_state(sim.mechanism, q, np.zeros(7)).C
    return np.concatenate([q, C @ velocity])
