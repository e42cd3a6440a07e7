"""``fmus.export.build.precompute``: the designs an FMU carries are those its initialisation
computes here with its start values (``resources/start_values.json``); a model that computes
none gets no file; one whose initialisation fails gets none, with a warning naming it and why
(issue 31: that branch ran in no test).  No FMU is built: the slaves run in process."""
from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

from fmus.export.build import precompute
from fmus.slave.base import START_VALUES_FILE
from fmus.slave.registry import SLAVES


def _precompute(tmp_path, model: str, values: dict | None = None):
    """(returned path, the file asked for, the warnings' messages) of ``model`` started at ``values``."""
    resources = tmp_path / "resources"
    resources.mkdir(parents=True)
    if values is not None:
        (resources / START_VALUES_FILE).write_text(json.dumps(values))
    path = tmp_path / "designs.npz"
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        returned = precompute(SLAVES[model], model, resources, path)
    return returned, path, [(w.category, str(w.message)) for w in caught]


def _index(path) -> list:
    with np.load(path) as data:
        return json.loads(str(data["index"]))


def test_the_designs_follow_the_start_values(tmp_path):
    """A drive's current controller is designed for its resistance: the default preset's
    (motor1) without start values, R = 2 ohm with them.  Catches the start values not read
    (the same design twice), the file not written where asked, or another path returned."""
    default, path, caught = _precompute(tmp_path / "a", "DCMotorDrive")
    assert default == path and path.is_file() and caught == []
    [[module, key]] = _index(path)
    assert module == "motor.current_controller" and key[0] == "current_controller" and key[1] != 2.0
    given, path, caught = _precompute(tmp_path / "b", "DCMotorDrive", {"R": 2.0})
    assert given == path and caught == []
    [[module, other]] = _index(path)
    assert module == "motor.current_controller" and other[1] == 2.0 and other[2:] == key[2:]


def test_the_derivators_designs_are_both_of_its_filters(tmp_path):
    """Catches designs recorded from an earlier model's (a module's dict not emptied first)
    or only the last one kept."""
    returned, path, _ = _precompute(tmp_path, "Derivator")
    assert returned == path
    assert sorted(module for module, _ in _index(path)) == ["controller.derivators"] * 2


@pytest.mark.parametrize("model", ["Trajectory", "FiveBarPlant"])
def test_a_model_that_designs_nothing_gets_no_file(tmp_path, model):
    """Catches an empty designs file written (every FMU would carry one) or a path returned
    for a file that is not there."""
    returned, path, caught = _precompute(tmp_path, model)
    assert returned is None and not path.exists() and caught == []


@pytest.mark.parametrize("values, why", [
    ({"R": -5.0}, "parameter R = -5.0 is negative (use -1 for the preset's value)"),
    ({"preset": "nope"}, "parameter preset = 'nope': unknown motor preset 'nope'; valid presets: motor1, motor2, "
                         "seed000"),
])
def test_an_initialisation_that_fails_gets_no_designs_and_one_warning_naming_it(tmp_path, values, why):
    """Catches a failed initialisation's (partial) designs written, the failure raised out of
    the build, or a warning that does not name the model and the slave's own message."""
    returned, path, caught = _precompute(tmp_path, "DCMotorDrive", values)
    assert returned is None and not path.exists()
    assert caught == [(UserWarning, "DCMotorDrive: its designs are not computed ahead, its initialisation here with "
                                    f"its start values failed: initialisation refused: {why} (t = 0 s)")]
