"""Current observer: estimate the armature current from voltage and speed.

The bench has no current sensor; the current controller is closed on an
estimate (thesis 7.2.4).
"""

import math

import numpy as np

import kernels
from motor import _checks, kernel
from motor.electrics import electrical_step_coefficients

#: Names accepted for ``CurrentObserver(kind=...)``.
OBSERVER_KINDS = ("static", "dynamic")


class CurrentObserver:
    """Open-loop current observer, static (7.20) or dynamic.

    ``"static"`` (7.20): i_hat = (v - ke omega) / R, the steady state of
    (4.163) (di/dt = 0), with v the voltage applied over the last step and
    omega the present speed. It ignores L: the estimate is the current the
    last voltage would reach after L/R has died out, one step late relative
    to the true current, so the loop sees 1/(R z) instead of G_I(z).

    ``"dynamic"``: (4.163) integrated exactly over the last step with the
    voltage v and the speed held over it (the speed passed at the previous
    call, since the drive holds omega from the start of the step); with
    matching parameters it reproduces the drive's current exactly.

    Parameters
    ----------
    params : motor.presets.MotorParams
        Uses R and ke (and L for the dynamic kind).
    kind : {"static", "dynamic"}
        Observer variant.
    """

    def __init__(self, params, kind="static"):
        params.validate()
        self.params = params
        self.kind = _checks.choice("kind", kind, OBSERVER_KINDS)
        self._method = "quasi_static" if kind == "static" else "exact"
        self._h = None
        # Constants and state of the step: the C struct pc_observer (kernels/src/observer.h).
        self.buf = np.zeros(kernels.size(kernel.OBSERVER))
        self.buf[_O["is_static"]] = 1.0 if kind == "static" else 0.0
        self.buf[_O["ke"]] = params.ke
        self.buf[_O["h"]] = math.nan     # no step prepared
        self._bind()
        self.reset()

    def _bind(self):
        """The C call on this observer's buffer (:class:`motor.kernel.Calls`)."""
        # A bound method only: FMU state treats it as code (an address must never be state).
        self._kernel = kernel.Calls.observer(self.buf).observer_estimate

    def __getstate__(self):
        return {k: v for k, v in self.__dict__.items() if k != "_kernel"}

    def __setstate__(self, state):
        self.__dict__.update(state)
        self._bind()

    i_hat = property(lambda self: float(self.buf[_O["i_hat"]]), doc="The last estimate [A].")

    def reset(self, i0=0.0, omega0=None):
        """Set the estimate ``i0`` [A]; ``omega0`` [rad/s] is the speed of the previous call."""
        b = self.buf
        b[_O["i_hat"]] = _checks.finite("i0", i0)
        b[_O["has_prev"]] = 0.0 if omega0 is None else 1.0
        b[_O["omega_prev"]] = 0.0 if omega0 is None else _checks.finite("omega0", omega0)

    def prepare_step(self, h):
        """Check the step length h and compute its coefficients (kept until h changes)."""
        h = _checks.positive("h", h)
        if h != self._h:
            a, g = electrical_step_coefficients(self.params.R, self.params.L, h, self._method)
            self.buf[_O["a"]], self.buf[_O["g"]] = a, g
            self.buf[_O["h"]] = h
            self._h = h

    def estimate(self, v, omega, h, time=None):
        """Current estimate at the end of a step.

        Parameters
        ----------
        v : float
            Voltage applied over the step that just ended [V].
        omega : float
            Speed now, at the end of that step [rad/s].
        h : float
            Length of that step [s].
        time : float, optional
            The time now [s], for the message of a refusal.

        Returns
        -------
        float
            Estimated current i_hat [A].

        Raises
        ------
        ValueError
            Naming the input, for a NaN/inf input or h <= 0; :class:`kernels.Refused` also
            for an estimate that is not finite (not kept).
        """
        try:
            code = self._kernel(v, omega, h)
        except TypeError:     # not a float: converted, or refused by name
            code = kernel.call(self._kernel, _INPUTS, (v, omega, h))
        if code == kernel.UNPREPARED_STEP:
            self.prepare_step(h)
            code = kernel.call(self._kernel, _INPUTS, (v, omega, h))
        calls = self._kernel.__self__
        if code == kernel.OK:
            return calls.x[3]
        at = "" if time is None else f" at t = {time:.6g} s"
        refused = kernels.refused(kernel.OBSERVER_REASONS, calls.refusal, time, at=at, v=v, omega=omega)
        names_time = at and "at" in kernel.OBSERVER_REASONS[calls.refusal.code].fields
        raise kernels.timed(refused) if names_time else refused


_O = kernel.indices(kernel.OBSERVER)
_INPUTS = ("v", "omega", "h")
