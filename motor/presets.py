"""DC motor parameters: the single source of truth (thesis Tables 16 and 18).

The thesis tables print the viscous coefficient ``b`` in "Ns"; the model
(B.2) needs N m s/rad, which is what is stored here. All values are SI.
"""

from dataclasses import dataclass, fields, replace

from motor import _checks


#: MotorParams fields that must be > 0 (the others must be >= 0).
POSITIVE_FIELDS = frozenset({"R", "kt", "ke", "J_rotor", "v_max", "omega_eps", "omega_s", "sigma0"})


@dataclass(frozen=True)
class MotorParams:
    """Parameters of one brushed DC motor and its driver.

    Parameters
    ----------
    R : float
        Armature resistance [ohm], > 0.
    L : float
        Armature inductance [H], >= 0 (0 means the quasi-static model).
    kt : float
        Torque constant [N m/A], > 0 (B.3: T = kt i).
    ke : float
        Back-emf constant [V s/rad], > 0 (4.162, B.1).
    b : float
        Viscous friction [N m s/rad], >= 0 (B.2).
    mu : float
        Coulomb (dry) friction torque [N m], >= 0 (B.2).
    J_rotor : float
        Rotor inertia [kg m^2], > 0. Integrated by the plant (4.139), used here
        only for the current-controller design model G_I(s) (B.10).
    v_max : float
        Supply voltage [V]: the driver saturates at +-v_max. Default 24.
    omega_eps : float
        Width [rad/s] of the regularised sign in the Coulomb friction,
        mu*tanh(omega/omega_eps); see :func:`motor.electrics.coulomb_friction`.
    mu_s : float
        Break-away (static) friction torque [N m], >= 0, of the LuGre friction
        (:mod:`motor.friction`, the drive's ``friction="lugre"``: Fs of (3), which needs
        mu_s >= mu > 0); 0 (the default) means "not given".
    omega_s : float
        Stribeck speed [rad/s], > 0 (LuGre (3)).
    sigma0 : float
        Bristle stiffness [N m/rad], > 0 (LuGre (1), (4)).
    sigma1 : float
        Bristle damping [N m s/rad], >= 0 (LuGre (4)).  The drive's coupling to the plant
        at a step h is stable for sigma0 h / 2 < sigma1 < 2 J / h (docs/friction.md).

    Raises
    ------
    ValueError
        On construction, naming the first non-physical parameter and its value.
    """

    R: float
    L: float
    kt: float
    ke: float
    b: float
    mu: float
    J_rotor: float
    v_max: float = 24.0
    omega_eps: float = 0.5
    mu_s: float = 0.0
    omega_s: float = 0.1
    sigma0: float = 100.0
    sigma1: float = 0.15

    def __post_init__(self):
        self.validate()

    def validate(self):
        """Raise ValueError naming the first non-physical parameter and its value.

        NaN/inf are rejected everywhere; R, kt, ke, J_rotor, v_max, omega_eps, omega_s,
        sigma0 must be > 0; L, b, mu, mu_s, sigma1 must be >= 0.
        """
        for f in fields(self):
            check = _checks.positive if f.name in POSITIVE_FIELDS else _checks.non_negative
            check(f.name, getattr(self, f.name))

    def with_(self, **changes):
        """Return a validated copy with some parameters replaced.

        Raises
        ------
        ValueError
            For an unknown parameter name or a non-physical value.
        """
        names = {f.name for f in fields(self)}
        unknown = sorted(set(changes) - names)
        if unknown:
            raise ValueError(f"unknown motor parameter(s) {unknown}; valid: {sorted(names)}")
        return replace(self, **changes)


#: LuGre friction of the thesis motors (the thesis identifies mu and b only, app. D): the
#: break-away torque 1.25 mu, the Stribeck speed 0.1 rad/s, the bristles 100 N m/rad (MotorParams defaults; the
#: presliding deflection at break-away mu_s / sigma0 ~ 0.6 mrad, two encoder counts) damped
#: by 0.15 N m s/rad, inside the 1 ms coupling's stability band sigma0 h / 2 < sigma1 <
#: 2 J / h for any inertia above the rotors' (docs/friction.md argues each value).
STICTION_RATIO = 1.25

#: Motor 1, thesis Table 16 (from appendix D, data of Table 15).
motor1 = MotorParams(R=1.101, L=0.667e-3, kt=5.598e-2, ke=5.138e-2,
                     b=1.226e-4, mu=4.357e-2, J_rotor=1.469e-4, mu_s=STICTION_RATIO * 4.357e-2)

#: Motor 2, thesis Table 18 (from appendix D, data of Table 17).
motor2 = MotorParams(R=0.829, L=0.667e-3, kt=5.666e-2, ke=5.200e-2,
                     b=2.039e-4, mu=4.992e-2, J_rotor=1.887e-4, mu_s=STICTION_RATIO * 4.992e-2)

#: The motor of seed 000 (the wheeled pendulum): R_m, K_t = K_e, f_m and n = 1 from the seed;
#: its inductance and rotor inertia are "negligible" there: L = 0 makes the drive's electrics
#: quasi-static ((22): i = (V - K_e omega)/R_m), and J_rotor, which only the current-controller
#: design reads, is a token 1e-9 kg m^2 (voltage mode never designs one).  f_m is the drive's
#: viscous b on the motor speed relative to the body.  v_max 8 V: the seed gives no battery
#: voltage, 8 V is our assumption (docs/pendulum.md).
seed000 = MotorParams(R=6.69, L=0.0, kt=0.4, ke=0.4, b=0.0022, mu=0.0, J_rotor=1e-9, v_max=8.0)

MOTOR_PRESETS = {"motor1": motor1, "motor2": motor2, "seed000": seed000}


def get_motor_preset(name):
    """Return the preset called ``name``.

    Parameters
    ----------
    name : str
        ``"motor1"``, ``"motor2"`` or ``"seed000"`` (the wheeled pendulum's motor).

    Returns
    -------
    MotorParams

    Raises
    ------
    ValueError
        For an unknown name, listing the valid ones.
    """
    try:
        return MOTOR_PRESETS[name]
    except (KeyError, TypeError):
        raise ValueError(f"unknown motor preset {name!r}; valid presets: "
                         f"{', '.join(sorted(MOTOR_PRESETS))}") from None
