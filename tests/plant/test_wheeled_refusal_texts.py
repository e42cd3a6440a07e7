"""The wheeled pendulum's refusal records (plant/wheeled.py's REASONS through refusal_error),
word for word for every code: the message, the reason, the variable the kernel's index picks,
its value, its unit and the time; a fall is a FallenError with the pitch at the last good state.
The records are made from the kernel's refusal record (some codes, BAD_SETTING and NONFINITE,
are all but unreachable by stepping a valid pendulum)."""
from __future__ import annotations

import math

import pytest

import kernels
from plant import wheeled_kernel as K
from plant.wheeled import REASONS, FallenError, refusal_error

T, PSI = 0.375, 0.5        # the time of the refusal [s], the pitch at the last good state [rad]
LAST_GOOD = f"at t = 0.375 s: psi = {math.degrees(PSI):.4g} deg at the last good state"

CASES = [
    ("FALLEN_PITCH", 0, 1.75, "psi", "rad", "fallen_pitch",
     "the robot fell over (pitch beyond 90 degrees) " + LAST_GOOD),
    ("FALLEN_FLOOR", 0, -0.5, "psi", "rad", "fallen_floor",
     "the robot fell over (body touching the floor) " + LAST_GOOD),
    ("NONFINITE", 6, math.inf, "dpsi", "", "nonfinite_state", "the state became non-finite " + LAST_GOOD),
    ("NONFINITE", 0, -math.inf, "theta", "", "nonfinite_state", "the state became non-finite " + LAST_GOOD),
    ("BAD_INPUT", 1, math.inf, "tau_r", "N m", "input_not_finite", "input tau_r = inf at t = 0.375 s is not finite"),
    ("BAD_STEP", 0, -0.001, "dt", "s", "bad_step", "step size -0.001 at t = 0.375 s must be > 0"),
    ("BAD_SETTING", 0, 0.0, "substeps", "", "bad_setting",
     f"setting substeps = 0.0 at t = 0.375 s is out of range (substeps: an integer in [1, {K.MAX_SUBSTEPS}]; "
     "count: > 0 rad)"),
    ("BAD_SETTING", 1, -1.0, "count", "", "bad_setting",
     f"setting count = -1.0 at t = 0.375 s is out of range (substeps: an integer in [1, {K.MAX_SUBSTEPS}]; "
     "count: > 0 rad)"),
    ("INPUT_LIMIT", 2, -3e6, "tau_d", "N m", "input_absurd",
     "input tau_d = -3000000.0 at t = 0.375 s is absurd: |tau_d| must be <= 1e+06"),
]


@pytest.mark.parametrize("code, index, value, variable, unit, reason, message", CASES,
                         ids=[f"{c[0]}-{c[1]}" for c in CASES])
def test_each_wheeled_refusal_record_reads_back_word_for_word(code, index, value, variable, unit, reason, message):
    """Catches a message that drops its explanation or a field, names another variable (an index
    off by one in a reason's variable list), or a reason whose name, unit or template is another's."""
    refused = refusal_error(kernels.Refusal(code=getattr(K, code), index=index, value=value), T, PSI, limit=1e6)
    assert str(refused) == message
    assert refused.record() == {"instance": None, "time": T, "variable": variable, "value": value, "unit": unit,
                                "code": getattr(K, code), "reason": reason, "message": message}
    assert refused.names_time
    assert isinstance(refused, FallenError) == (getattr(K, code) in K.FALLS)
    if isinstance(refused, FallenError):
        assert refused.psi == PSI


def test_every_wheeled_code_has_a_reason_of_its_own():
    """Catches a code read with another code's reason (two records that cannot be told apart)."""
    assert len({reason.name for reason in REASONS.values()}) == len(REASONS) == 7
