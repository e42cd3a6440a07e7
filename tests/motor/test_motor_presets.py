"""Motor presets (Tables 16, 18) and parameter validation."""

import math
import re
from pathlib import Path

import pytest

from motor import MOTOR_PRESETS, MotorParams, get_motor_preset, motor1, motor2
from motor.presets import STICTION_RATIO


def test_presets_match_system_md():
    """Catches a motor preset whose value differs from Tables 16 and 18 (SYSTEM.md), or a copy instead of the preset."""
    assert (motor1.R, motor1.L, motor1.b, motor1.kt, motor1.mu, motor1.ke, motor1.J_rotor) == \
        (1.101, 0.667e-3, 1.226e-4, 5.598e-2, 4.357e-2, 5.138e-2, 1.469e-4)
    assert (motor2.R, motor2.L, motor2.b, motor2.kt, motor2.mu, motor2.ke, motor2.J_rotor) == \
        (0.829, 0.667e-3, 2.039e-4, 5.666e-2, 4.992e-2, 5.200e-2, 1.887e-4)
    assert motor1.v_max == motor2.v_max == 24.0
    assert get_motor_preset("motor1") is motor1 and get_motor_preset("motor2") is motor2


def test_unknown_preset_lists_valid_ones():
    """Catches an unknown preset refused without listing the valid names, or a preset added or lost."""
    with pytest.raises(ValueError, match=r"'motor3'.*motor1, motor2, seed000"):
        get_motor_preset("motor3")
    assert sorted(MOTOR_PRESETS) == ["motor1", "motor2", "seed000"]


def test_seed000_preset_is_the_seed_motor():
    """Seed 000's parameter list: R_m 6.69, K_t = K_e = 0.4, f_m 0.0022, L negligible; 8 V
    battery (our assumption)."""
    p = get_motor_preset("seed000")
    assert (p.R, p.kt, p.ke, p.b, p.mu, p.L, p.v_max) == (6.69, 0.4, 0.4, 0.0022, 0.0, 0.0, 8.0)


@pytest.mark.parametrize("name, value", [
    ("R", 0.0), ("R", -1.0), ("R", math.nan), ("L", -1e-3), ("L", math.inf), ("kt", 0.0),
    ("ke", -0.05), ("b", -1e-4), ("mu", math.nan), ("J_rotor", 0.0), ("v_max", -24.0),
    ("omega_eps", 0.0),
])
def test_non_physical_parameter_named(name, value):
    """Catches a motor parameter check that is missing or whose message does not name the field and its value."""
    with pytest.raises(ValueError, match=rf"^{name} must .*{value!r}"):
        motor1.with_(**{name: value})


def test_with_replaces_and_rejects_unknown_names():
    """Catches with_() changing other fields, accepting a misspelled name, or skipping the physical checks."""
    m = motor1.with_(L=0.0, mu=0.0)
    assert (m.L, m.mu, m.R) == (0.0, 0.0, motor1.R)
    with pytest.raises(ValueError, match="unknown motor parameter.*'Rx'"):
        motor1.with_(Rx=1.0)
    with pytest.raises(ValueError, match="R must be > 0"):
        MotorParams(R=-1, L=1e-3, kt=0.05, ke=0.05, b=0, mu=0, J_rotor=1e-4)


def _friction_table():
    """{parameter: (motor1 value, motor2 value)} of docs/friction.md's table of the presets'
    LuGre parameters (the numbers before the units)."""
    text = (Path(__file__).resolve().parents[2] / "docs" / "friction.md").read_text()
    rows = re.findall(r"^\| `(\w+)` \([^)]*\) \| ([0-9.e-]+) [^|]*\| ([0-9.e-]+) [^|]*\|", text, flags=re.M)
    return {name: (float(a), float(b)) for name, a, b in rows}


def test_the_presets_lugre_parameters_are_docs_friction_mds():
    """Break-away 1.25 mu (``STICTION_RATIO``) of each motor's own mu, the Stribeck speed, the
    bristles' stiffness and damping as docs/friction.md's table gives them (its mu_s to the
    4 figures printed)."""
    table = _friction_table()
    assert set(table) == {"mu_s", "omega_s", "sigma0", "sigma1"}
    assert STICTION_RATIO == 1.25
    for k, m in enumerate((motor1, motor2)):
        assert m.mu_s == pytest.approx(1.25 * m.mu, rel=1e-15)
        assert m.mu_s == pytest.approx(table["mu_s"][k], abs=0.5e-5)
        assert (m.omega_s, m.sigma0, m.sigma1) == (table["omega_s"][k], table["sigma0"][k], table["sigma1"][k])


def test_seed000_has_no_friction_but_its_viscous_term_and_a_token_rotor():
    """Seed 000's motor: no Coulomb nor break-away torque, J_rotor the token 1e-9 kg m^2."""
    p = get_motor_preset("seed000")
    assert (p.mu, p.mu_s, p.J_rotor) == (0.0, 0.0, 1e-9)
