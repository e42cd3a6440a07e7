"""What a native FMU is made of (fmus/native/models.py ``NATIVE``): each model's C parts, and
the drive data it carries (``drive_design``, ``drive_presets``), row by row against the
motors it is said to carry.

The native FMU looks a design up by its motor's row and designs in C only when none matches
(tests/fmus/native/test_native_design.py compares the results): a row missing, doubled,
out of order or with another T still gives equal results there, so the rows themselves are
held here to the docstring: the slave's own motor (or its design parameters) first, then
each motor preset not already carried, at the slave's T; each row's coefficients the
python-control design (app. C) of that motor.
"""
from __future__ import annotations

import numpy as np
import pytest

from fmus.native.models import drive_design, drive_presets
from fmus.slave.declarations import MOTOR_PARAMETERS
from motor.current_controller import THESIS_POLES, design_current_controller
from motor.presets import MOTOR_PRESETS
from tests.fmus.slave.test_extremes import make_slave
from tests.support.paths import ROOT

ROW = ("R", "L", "kt", "ke", "b", "J_rotor")


def _designable(p, T: float) -> bool:
    try:
        design_current_controller(p, T, THESIS_POLES)
    except ValueError:
        return False
    return True


def _expected_rows(first, T: float) -> list:
    """The slave's motor, then each preset (by sorted name) that has a design (a quasi-static
    preset, L = 0, has none) and is not carried yet."""
    rows = [[getattr(first, f) for f in ROW] + [T]]
    for p in (MOTOR_PRESETS[n] for n in sorted(MOTOR_PRESETS)):
        row = [getattr(p, f) for f in ROW] + [T]
        if row not in rows and _designable(p, T):
            rows.append(row)
    return rows


@pytest.mark.parametrize("parameters", [{}, {"T": 2e-4}, {"R_design": 2.0, "b_design": 3e-4},
                                        {"preset": "motor2", "kt": 0.07}])
def test_a_drive_carries_its_own_design_first_then_each_other_preset_once_at_its_T(parameters):
    """Catches a row skipped or repeated (the dedup inverted), the presets out of order, the
    slave's T not in the rows, the design parameters not the first row, and coefficients of
    another motor or T."""
    slave = make_slave("DCMotorDrive", parameters)
    first = MOTOR_PRESETS[parameters.get("preset", "motor1")].with_(
        **{k: v for k, v in parameters.items() if k in ROW})
    first = first.with_(**{k.split("_")[0]: v for k, v in parameters.items() if k.endswith("_design")})
    data = drive_design(slave)
    rows = _expected_rows(first, slave.T)
    assert data["design_keys"].tolist() == rows
    assert data["design_error"] == [""]
    for row, coefficients in zip(rows, data["design_coefficients"].tolist()):
        motor = MOTOR_PRESETS["motor1"].with_(**dict(zip(ROW, row[:6])))
        d = design_current_controller(motor, row[6], THESIS_POLES)
        assert coefficients == [d.alpha, d.beta, d.gamma, d.delta]


def test_a_drive_whose_own_design_fails_carries_zeros_first_and_the_message():
    """L = 0 (voltage mode, quasi-static) has no current controller: its row is carried with
    zero coefficients and the design's message, the presets after it.  Catches the failed row
    dropped (the C side would then design it and fail differently) or its message lost."""
    slave = make_slave("DCMotorDrive", {"L": 0.0, "mode": "voltage"})
    data = drive_design(slave)
    own = MOTOR_PRESETS["motor1"].with_(L=0.0)
    assert data["design_keys"].tolist() == _expected_rows(own, slave.T)
    assert data["design_coefficients"][0].tolist() == [0.0] * 4
    assert data["design_error"][0].startswith("current controller design (app. C) failed for R = 1.101, L = 0.0")
    assert np.all(data["design_coefficients"][1:] != 0.0)


def test_each_drive_of_an_actuated_plant_carries_its_own_suffixed_design():
    """Catches the suffix not read (drive 2 carrying drive 1's motor) or not written into the
    data's names."""
    slave = make_slave("ActuatedFiveBarPlant", {"preset2": "motor2", "R1": 1.5})
    data = {**drive_design(slave, "1"), **drive_design(slave, "2")}
    assert data["design1_keys"].tolist() == _expected_rows(MOTOR_PRESETS["motor1"].with_(R=1.5), slave.T)
    assert data["design2_keys"].tolist() == _expected_rows(MOTOR_PRESETS["motor2"], slave.T)


def test_the_motor_presets_are_carried_by_sorted_name_one_row_of_every_motor_parameter():
    """Catches presets out of the order their names are looked up in, or a field of
    MOTOR_PARAMETERS missing or shifted."""
    data = drive_presets()
    names = sorted(MOTOR_PRESETS)
    assert data["preset_names"] == names
    fields = [f for f, _, _ in MOTOR_PARAMETERS]
    assert data["preset_motor"].tolist() == [[getattr(MOTOR_PRESETS[n], f) for f in fields] for n in names]
    assert data["current_poles"].tolist() == list(THESIS_POLES)


def test_every_native_model_names_its_own_adapter_and_kernel_sources_that_exist():
    """Each NATIVE entry: the adapter pcn_<model>.c in fmus/native/adapters, kernels as C files
    of kernels/src, parts in fmus/native/adapters, data a function (NativeModel's docstring).
    Catches an entry's fields swapped or misnamed, which only the minutes-long builds of
    that one model would otherwise meet."""
    from fmus.native.models import NATIVE

    root = ROOT
    for model, native in NATIVE.items():
        assert native.adapter == f"pcn_{model.lower()}.c", model
        assert (root / "fmus" / "native" / "adapters" / native.adapter).is_file(), model
        assert isinstance(native.kernels, tuple) and native.kernels, model
        for name in native.kernels:
            assert name.endswith(".c") and (root / "kernels" / "src" / name).is_file(), (model, name)
        for name in native.parts:
            assert (root / "fmus" / "native" / "adapters" / name).is_file(), (model, name)
        assert callable(native.data), model


def test_a_native_model_is_sampled_exactly_when_its_slave_has_a_sample_period():
    """``sampled`` puts pcn_sampling.c and the kernels' counting rule into the FMU; the slave's
    ``has_sample_period`` (fmus/slave/sampling.py) says whether the model keeps a sample time.
    Catches an entry's flag flipped or left at its default, which only that model's build and
    twin comparison would meet."""
    import importlib

    from fmus.native.models import NATIVE
    from fmus.slave.registry import SLAVES

    flags = {}
    for model, native in NATIVE.items():
        slave = getattr(importlib.import_module(f"fmus.slaves.{SLAVES[model]}"), model)
        flags[model] = (native.sampled, bool(getattr(slave, "has_sample_period", False)))
    assert {m: s for m, (s, _) in flags.items()} == {m: p for m, (_, p) in flags.items()}
    assert any(s for s, _ in flags.values()) and not all(s for s, _ in flags.values())


def test_the_derivator_carries_the_buffer_designed_for_its_own_cutoffs_and_sample_time():
    """The slave's fc_vel, fc_acc and T (three different values), given to the design by name
    here: the carried buffer (two channels) and the scalars are theirs.  Catches two of them
    passed in each other's place, which only a native Derivator's build and run would meet."""
    from types import SimpleNamespace

    from controller.derivators import Derivator
    from fmus.native.models import NATIVE

    slave = SimpleNamespace(derivator=Derivator(), fc_vel=40.0, fc_acc=15.0, T=1e-3)
    scalars, arrays = NATIVE["Derivator"].data(slave)
    expected = Derivator(fc_vel=40.0, fc_acc=15.0, T=1e-3)
    expected.start_at_first_sample(2)
    np.testing.assert_array_equal(arrays["design_buffer"], expected.buf)
    assert scalars == {"derivator_states": int(expected.buf[0]), "design_fc_vel": 40.0, "design_fc_acc": 15.0,
                       "design_t": 1e-3}
