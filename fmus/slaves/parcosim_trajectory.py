"""FMI slave ``Trajectory``: the reference x_d, y_d and its derivatives (thesis 7.18, 7.23-7.27).

Timing convention: after ``doStep(t, h)`` the outputs are the reference at the END of the
step, t + h; after initialisation they are the reference at the experiment's start time
(``setupExperiment``, normally 0).  A master that samples the controller at t therefore reads
the trajectory's outputs from the previous step (or from initialisation at t = 0): the
values at exactly t.  No inputs, so no feedthrough.

The module name is unique among parcosim slaves: all FMUs loaded in one
process share one Python interpreter and its module cache.
"""
from __future__ import annotations

from controller.trajectories import PARAMETERS, from_parameters, parameters_of, sample_buffers, sample_values
from fmus.slave.base import GuardedSlave
from fmus.slave.refusals import refuse_absurd, refuse_tiny, require_finite

OUTPUTS = ("x_d", "y_d", "dx_d", "dy_d", "ddx_d", "ddy_d")


class Trajectory(GuardedSlave):
    """Analytic reference trajectory of the end effector (thesis 7.18, 7.23-7.27)."""

    author = "parcosim"
    description = "Reference trajectory (Coutinho 2019, 7.18, 7.23-7.27): x_d, y_d and derivatives at the end of each step"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        d = self.declare
        for name, text in (("x_d", "Reference x [m]"), ("y_d", "Reference y [m]"),
                           ("dx_d", "d x_d/dt [m/s]"), ("dy_d", "d y_d/dt [m/s]"),
                           ("ddx_d", "d2 x_d/dt2 [m/s2]"), ("ddy_d", "d2 y_d/dt2 [m/s2]")):
            d(name, "output", 0.0, f"{text}, at the end of the last step")
        d("x_start", "output", 0.0, "Where the mechanism starts at rest, x [m] (7.17, 7.28)")
        d("y_start", "output", 0.0, "Where the mechanism starts at rest, y [m] (7.17, 7.28)")
        for name, text in (("kind", "'thesis_circle' (7.18), 'circle' (7.23), 'triangle' (7.24-7.27), 'hold'"),
                           ("cycles", "Cycles of circle/triangle (-1: thesis_circle 2, circle 8, triangle 2)"),
                           ("side_time", "Triangle: time per side [s]"),
                           ("frequency", "circle: turns per second [Hz] (the thesis' 7.23: 1)"),
                           ("x_hold", "hold: the point held, x [m] (default x_1, 7.28)"),
                           ("y_hold", "hold: the point held, y [m] (default x_1, 7.28)")):
            d(name, "parameter", PARAMETERS[name], text)
        self.trajectory = None
        self.__buffers = sample_buffers()   # reused by every sample; "__": not FMU state

    def setup(self):
        values = parameters_of(self)
        used_or_not = {name: value for name, value in values.items() if isinstance(PARAMETERS[name], float)}
        require_finite(**used_or_not)
        refuse_absurd(**used_or_not)
        refuse_tiny(side_time=self.side_time)     # the triangle divides by side_time squared
        self.trajectory = from_parameters(**values)
        self.x_start, self.y_start = (float(v) for v in self.trajectory.start_point)
        self._publish(self._start_time)

    def step(self, current_time, step_size):
        self._publish(current_time + step_size)

    def _publish(self, t):
        values, refusal = self.__buffers   # the OUTPUTS, stored one attribute after another (no zip, no dict)
        self.x_d, self.y_d, self.dx_d, self.dy_d, self.ddx_d, self.ddy_d = sample_values(self.trajectory, t, values,
                                                                                         refusal)
