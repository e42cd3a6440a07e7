"""Current observer: estimate the armature current from voltage and speed.

The bench has no current sensor; the current controller is closed on an
estimate (thesis 7.2.4).
"""

import math

import numpy as np

from motor import _checks, fastdrive
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
        # Constants and state of the per-step arithmetic (motor.fastdrive's layout).
        self.buf = np.zeros(fastdrive.OBSERVER_SIZE)
        self.buf[fastdrive.O_STATIC] = 1.0 if kind == "static" else 0.0
        self.buf[fastdrive.O_KE] = params.ke
        self.buf[fastdrive.O_H] = math.nan     # no step prepared
        self.reset()
        fastdrive.observer_estimate(self.buf.copy(), 0.0, 0.0, math.nan)   # compile now, not in a step

    i_hat = property(lambda self: float(self.buf[fastdrive.O_I_HAT]), doc="The last estimate [A].")

    def reset(self, i0=0.0, omega0=None):
        """Set the estimate ``i0`` [A]; ``omega0`` [rad/s] is the speed of the previous call."""
        b = self.buf
        b[fastdrive.O_I_HAT] = _checks.finite("i0", i0)
        b[fastdrive.O_HAS_PREV] = 0.0 if omega0 is None else 1.0
        b[fastdrive.O_OMEGA_PREV] = 0.0 if omega0 is None else _checks.finite("omega0", omega0)

    def prepare_step(self, h):
        """Check the step length h and compute its coefficients (kept until h changes)."""
        h = _checks.positive("h", h)
        if h != self._h:
            a, g = electrical_step_coefficients(self.params.R, self.params.L, h, self._method)
            self.buf[fastdrive.O_A], self.buf[fastdrive.O_G] = a, g
            self.buf[fastdrive.O_H] = h
            self._h = h

    def estimate(self, v, omega, h):
        """Current estimate at the end of a step.

        Parameters
        ----------
        v : float
            Voltage applied over the step that just ended [V].
        omega : float
            Speed now, at the end of that step [rad/s].
        h : float
            Length of that step [s].

        Returns
        -------
        float
            Estimated current i_hat [A].

        Raises
        ------
        ValueError
            Naming the input, for a NaN/inf input or h <= 0.
        """
        try:
            args = float(v), float(omega), float(h)
        except (TypeError, ValueError):
            args = math.nan, math.nan, math.nan
        status, i_hat = fastdrive.observer_estimate(self.buf, *args)
        if status == fastdrive.UNPREPARED_STEP:
            _checks.finite("v", v)
            _checks.finite("omega", omega)
            self.prepare_step(h)
            status, i_hat = fastdrive.observer_estimate(self.buf, *args)
        if status == fastdrive.NONFINITE_INPUT:
            _checks.finite("v", v)
            _checks.finite("omega", omega)
        return i_hat
