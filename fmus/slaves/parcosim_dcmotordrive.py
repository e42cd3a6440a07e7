"""FMI slave ``DCMotorDrive``: a thin adapter over :class:`motor.Drive`.

Timing (one communication step from t to t + h, inputs held over it):
``v`` is the voltage applied over [t, t + h] (in current mode the controller
samples ``i_ref`` and ``i_hat`` at t on the sub-step ``sample_phase`` of each period T,
steps h = T / n, and holds its voltage until the next sample; the electrics and the
torque advance on every step), ``i`` and
``tau`` are the current and shaft torque at t + h (with ``torque_output = "mean"``,
``tau`` is the shaft torque averaged over [t, t + h]).  Outputs change only in
``doStep``: no direct feedthrough.

``internal_observer``: the current loop closed inside the drive, on the estimate of
:class:`motor.CurrentObserver` from the voltage applied over the step just taken and the
speed input ``omega`` (thesis 7.20, as the instance ``CurrentObserver`` wired
``drive.v -> obs.v``, ``obs.i_hat -> drive.i_hat`` gives it; the input ``i_hat`` unused): no
connection of a Jacobi master inside the 1 ms current loop (docs/ssp.md).

The module name is unique among parcosim slaves: all FMUs loaded in one
process share one Python interpreter and its module cache.
"""
from __future__ import annotations

from fmus.slave import designs
from fmus.slave.base import MIN_STEP, GuardedSlave
from fmus.slave.refusals import refuse_absurd
from fmus.slave.declarations import CurrentLoopSteps, build_drive, declare_drive_options, declare_motor
from fmus.slave.sampling import declare_sample_phase

OUTPUTS = ("tau", "v", "i")


class DCMotorDrive(CurrentLoopSteps, GuardedSlave):
    """DC motor with its 1 ms discrete current controller (thesis 4.162, B.2, app. C, 7.2.10)."""

    author = "parcosim"
    description = ("DC motor drive (Coutinho 2019, 4.162, B.2, app. C): current reference or voltage in, "
                   "shaft torque out")

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        designs.load(self.resources)   # what its build computed ahead (fmus/slave/designs.py)
        d = self.declare
        d("i_ref", "input", 0.0, "Current reference, sampled at the step start (current mode) [A]")
        d("v_ref", "input", 0.0, "Commanded voltage, applied over the step, saturated at +-v_max (voltage mode) [V]")
        d("omega", "input", 0.0, "Shaft speed, held over the step [rad/s]")
        d("i_hat", "input", 0.0, "Observed (or measured) current at the step start (current mode) [A]")
        d("tau", "output", 0.0, "Shaft torque kt i - friction (B.2 or LuGre) at the step end [N m]")
        d("v", "output", 0.0, "Voltage applied over the step just taken [V]")
        d("i", "output", 0.0, "Armature current at the step end [A]")
        declare_motor(self)
        declare_drive_options(self)
        d("mode", "parameter", "current", "'current' (controller K(z) on i_ref, i_hat) or 'voltage' (v_ref applied)")
        d("method", "parameter", "exact",
          "Electrical integration over a step: 'exact' (analytic), 'euler' (explicit) or 'quasi_static' (L = 0)")
        d("torque_output", "parameter", "end",
          "'end': tau is the shaft torque at the step's end; 'mean': its average over the step "
          "(what a plant holding tau over the step should get)")
        d("T", "parameter", 1e-3, "Current-controller sample time [s]; in current mode the step must divide it")
        declare_sample_phase(self)
        d("internal_observer", "parameter", False,
          "Current mode: the controller reads the drive's own current estimate, the observer of 7.20 on the "
          "voltage it applied over the last step and the speed input omega, instead of the input i_hat "
          "(the current loop closed inside the drive FMU)")
        d("observer_kind", "parameter", "static",
          "The internal observer: 'static' ((v - ke omega)/R, 7.20) or 'dynamic' (motor.CurrentObserver)")
        d("omega0", "parameter", 0.0, "Start in electrical steady state at this speed [rad/s]")
        d("i0", "parameter", 0.0, "Start in electrical steady state with this current [A]")
        self.drive = None
        self.observer = None

    def setup(self):
        refuse_absurd(T=self.T, omega0=self.omega0, i0=self.i0)
        if 0.0 < self.T < MIN_STEP:
            raise ValueError(f"parameter T = {self.T!r} s must be >= {MIN_STEP:g} s")
        self.drive = build_drive(self, mode=self.mode, method=self.method, T=self.T,
                                 torque_output=self.torque_output, sample_phase=self.sample_phase)
        self.drive.start(self.omega0, self.i0)
        self.observer = self._internal_observer()
        self.tau = self.drive.torque(self.omega0)
        self.v = self.drive.v
        self.i = self.drive.i

    def current_loops(self):
        return [self.drive]

    def _internal_observer(self):
        """The drive's own :class:`motor.CurrentObserver` (``internal_observer``), or None."""
        from motor import OBSERVER_KINDS

        if self.observer_kind not in OBSERVER_KINDS:   # checked even when unused: a typo is not silent
            raise ValueError(f"parameter observer_kind = {self.observer_kind!r} must be one of "
                             f"{', '.join(map(repr, OBSERVER_KINDS))}")
        if not self.internal_observer:
            return None
        if self.mode != "current":
            raise ValueError(f"parameter internal_observer = {self.internal_observer!r} needs mode = 'current' (mode = "
                             f"{self.mode!r}: "
                             "no current controller reads an estimate)")
        from motor import CurrentObserver
        from motor._checks import BadValue

        try:
            observer = CurrentObserver(self.drive.params, self.observer_kind)
        except BadValue as exc:
            raise exc.renamed({"kind": "observer_kind"}) from None
        observer.reset(self.i0, self.omega0)
        return observer

    def step(self, current_time, step_size):
        i_hat = self.i_hat
        if self.observer is not None:   # from the voltage of the step just taken and the speed now
            i_hat = self.observer.estimate(self.v, self.omega, step_size, current_time)
        self.tau, self.v, self.i = self.drive.step(self.i_ref, self.v_ref, self.omega, i_hat, step_size)
