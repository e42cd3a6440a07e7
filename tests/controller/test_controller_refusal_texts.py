"""The position law's refusal records (controller/position.py's REASONS through
PositionController._refused), word for word for every code that is not a table's: the
message, the reason, the variable the record names, its value and the time.  Some codes
(REF_SINGULAR: a reference exactly on a chain's stretched or folded circle; EXACT_OUT) are
all but unreachable by stepping, so their records are made from the kernel's refusal record."""
from __future__ import annotations

import pytest

import kernels
from controller import law
from controller.position import PositionController
from controller.strategies import get_strategy
from plant import get_preset

#: q1, q2, dq1, dq2, ddq1, ddq2, x_d, y_d, dx_d, dy_d, ddx_d, ddy_d
INPUTS = [0.5, 2.25, 0.125, -0.25, 3.0, -40.0, 0.0125, 0.1875, 0.5, -0.75, 1.5, -2.5]
T = 0.375
REFERENCE = "reference (x_d, y_d) = (0.0125, 0.1875) m at t = 0.375 s"
MEASURED = "measured (q1, q2) = (0.5, 2.25) rad at t = 0.375 s: "
POSE = "measured pose (x, y) = (0.03125, 0.15625) m at t = 0.375 s: "

CASES = [
    ("NONFINITE", 4, 1e300, "ddq1", "input ddq1 = 1e+300 at t = 0.375 s is not finite"),
    ("NONFINITE", 11, -1e300, "ddy_d", "input ddy_d = -1e+300 at t = 0.375 s is not finite"),
    ("REF_OUT", 1, 0.3, "(x_d, y_d)", REFERENCE + " is outside the workspace"),
    ("REF_BAND", 0, 0.0625, "margin", REFERENCE + " is in the near-singular band (margin 0.0625 < 0.1)"),
    ("MEASURED_SINGULAR", 0, 1.5e-17, "(q1, q2)", MEASURED + "a parallel singularity (det J_X = 1.5e-17)"),
    ("REF_SINGULAR", 0, 0.0, "(x_d, y_d)", REFERENCE + ": a chain is stretched or folded there (J_Theta singular)"),
    ("EXACT_OUT", 0, 0.3125, "(x, y)", POSE + "point out of reach of a chain (distance 0.3125 m)"),
    ("NONFINITE_OUTPUT", 2, float("inf"), "i_ref1",
     "the law's outputs (tau1, tau2, i_ref1, i_ref2, e1, e2) = (1.0, 2.0, inf, 4.0, 5.0, 6.0) at t = 0.375 s are "
     "not finite; largest input: ddq2 = -40.0"),
]


@pytest.mark.parametrize("reason, index, value, variable, message", CASES, ids=[f"{c[0]}-{c[1]}" for c in CASES])
def test_each_refusal_record_reads_back_word_for_word(reason, index, value, variable, message):
    """Catches a message that drops its explanation or a field, names another variable (an index
    off by one in a reason's variable list), another value or time, or a wrong band."""
    ctrl = PositionController(get_preset("bench"), get_strategy("PDq"))
    assert ctrl.band == 0.1
    ctrl._scratch[law.POSE] = 0.03125, 0.15625
    ctrl._scratch[law.OUT] = 1.0, 2.0, float("inf"), 4.0, 5.0, 6.0
    refused = ctrl._refused(kernels.Refusal(code=getattr(law, reason), index=index, value=value), T, INPUTS)
    assert str(refused) == message
    record = refused.record()
    assert (record["variable"], record["value"], refused.time) == (variable, value, T)
    assert record["reason"] == reason
