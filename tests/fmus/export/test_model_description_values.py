"""Every slave's modelDescription.xml (pythonfmu's ``to_xml``, what the build writes) read back:
each start value parsed by its type equals the slave's own value exactly, and a sampled
slave's DefaultExperiment stepSize is its T, also at 2.5 ms and at a T of 17 significant
digits (issue 31, pattern 3: exported values read back and compared exactly).

pythonfmu writes a Real start with 16 significant digits (``f"{value:.16g}"``), which does not
give back about a quarter of all doubles; the first test is what would show a default of 17
digits that the model description cannot carry."""
from __future__ import annotations

import pytest

from fmus.cosim.backends import InProcessInstance
from fmus.slave.registry import SLAVES

PARSE = {"Real": float, "Integer": int, "Boolean": lambda text: {"true": True, "false": False}[text],
         "String": str, "Enumeration": int}
SAMPLED = ("Derivator", "PositionController", "BalanceController", "CurrentObserver", "DCMotorDrive",
           "ActuatedFiveBarPlant")


def _slave(model):
    return InProcessInstance(model, model.lower()).slave


@pytest.mark.parametrize("model", sorted(SLAVES))
def test_each_start_value_reads_back_as_the_slaves_own_value(model):
    """Catches a start written that is not the value the slave starts with (a declaration's
    default changed on one side only, a type written as another), or one that does not
    round-trip through the text."""
    slave = _slave(model)
    root = slave.to_xml()
    checked = 0
    for variable in root.find("ModelVariables"):
        (typed,) = list(variable)
        start = typed.get("start")
        if start is None:
            continue
        value = PARSE[typed.tag](start)
        own = getattr(slave, variable.get("name"))
        assert value == own and type(value) is type(own), (variable.get("name"), start, own)
        checked += 1
    assert checked >= 3


@pytest.mark.parametrize("model", SAMPLED)
@pytest.mark.parametrize("T", [2.5e-3, 1 / 300])
def test_a_sampled_slaves_default_step_is_its_sample_time_to_the_last_bit(model, T):
    """T = 2.5 ms and 1/300 s (0.0033333333333333335, 17 digits): stepSize reads back as T.
    Catches the default experiment's step taken from the default 1 ms, or written rounded."""
    slave = _slave(model)
    slave.T = T
    root = slave.to_xml()
    assert float(root.find("DefaultExperiment").get("stepSize")) == T
    assert float(root.find("DefaultExperiment").get("startTime")) == 0.0
