"""Current observer: estimate the armature current from voltage and speed.

The bench has no current sensor; the current controller is closed on an
estimate (thesis 7.2.4).
"""

from motor import _checks
from motor.electrics import advance_current, electrical_step_coefficients

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
        self._coefficients = None
        self.reset()

    def reset(self, i0=0.0, omega0=None):
        """Set the estimate ``i0`` [A]; ``omega0`` [rad/s] is the speed of the previous call."""
        self.i_hat = _checks.finite("i0", i0)
        self._omega_prev = None if omega0 is None else _checks.finite("omega0", omega0)

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
        v = _checks.finite("v", v)
        omega = _checks.finite("omega", omega)
        h = _checks.positive("h", h)
        if h != self._h:
            self._coefficients = electrical_step_coefficients(self.params.R, self.params.L, h, self._method)
            self._h = h
        omega_held = omega if self.kind == "static" or self._omega_prev is None else self._omega_prev
        self.i_hat = advance_current(self.i_hat, v, omega_held, self.params.ke, self._coefficients)
        self._omega_prev = omega
        return self.i_hat
