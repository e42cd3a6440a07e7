"""A PositionController refusal is recorded at the communication point of the step it refuses
(its ``refusal`` record and its ``error`` text), not at another time the step knows: after
five accepted 1 ms steps, the sixth, from t = 5 ms, refused by the law (a reference of 1e300 m, outside the
workspace).  Training sample 4263's [2], the step size passed to the law as its time, survived
every test: they refused at t = 0 only, or did not read the time."""
from __future__ import annotations

from fmus.status import RunError
from tests.fmus.slave.test_extremes import make_slave


def test_a_refused_sample_is_recorded_at_its_own_communication_point():
    slave = make_slave("PositionController")
    h = 1e-3
    for k in range(5):
        assert slave.do_step(k * h, h) is not False, slave.error
    slave.set_real([next(v.value_reference for v in slave.vars.values() if v.name == "x_d")], [1e300])
    assert slave.do_step(5 * h, h) is False
    record = RunError.from_json(slave.refusal)
    assert record.time == 5 * h and record.variable == "(x_d, y_d)", record
    assert "t = 0.005 s" in slave.error, slave.error
