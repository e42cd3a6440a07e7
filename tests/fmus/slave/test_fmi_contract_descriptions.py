"""Every variable's description in every parcosim model description (fmus/slave/base.py
``declare``, ``to_xml``): present, not its name, and for the parameters declared from a
table (fmus/slave/declarations.py CHAIN_PARAMETERS, MOTOR_PARAMETERS) that table's text, read
back from the XML an importer shows its users.
"""
from __future__ import annotations

import importlib

import pytest

from fmus.slave.declarations import CHAIN_PARAMETERS, MOTOR_PARAMETERS
from fmus.slave.registry import SLAVES


def _descriptions(model: str) -> dict:
    cls = getattr(importlib.import_module(f"fmus.slaves.{SLAVES[model]}"), model)
    root = cls(instance_name=model.lower()).to_xml()
    return {v.get("name"): v.get("description") for v in root.find("ModelVariables")}


@pytest.mark.parametrize("model", sorted(SLAVES))
def test_every_variable_is_described_in_words_not_by_its_name(model):
    """Catches a declaration that writes the name, or nothing, as the description."""
    described = _descriptions(model)
    assert described
    for name, text in described.items():
        assert text and text != name and len(text) > len(name) // 2, (model, name, text)


def test_the_table_parameters_carry_their_tables_text():
    """Catches a table's text put on another variable (a chain's on the other chain, a
    field's on another field) or replaced."""
    plant = _descriptions("FiveBarPlant")
    for k in (1, 2):
        for field, text in CHAIN_PARAMETERS:
            assert plant[f"chain{k}_{field}"] == f"Chain {k}: {text}; -1: the preset's value"
    drive, actuated = _descriptions("DCMotorDrive"), _descriptions("ActuatedFiveBarPlant")
    for _, var, text in MOTOR_PARAMETERS:
        assert drive[var] == f"{text}; -1: the preset's value"
        assert actuated[f"{var}1"] == actuated[f"{var}2"] == f"{text}; -1: the preset's value"
