"""The motor FMUs' parameter defaults as docs/motor.md's variable tables state them (the user's reference),
read from the tables here and compared with each slave's declared start (issue 31: zero-by-default
parameters and defaults held against the cited text, not against themselves)."""
from __future__ import annotations

import importlib
import re
from pathlib import Path

import pytest

from fmus.slave.registry import SLAVES

DOC = Path(__file__).resolve().parents[3] / "docs" / "motor.md"


def documented_defaults(section: str) -> dict:
    """name -> default of the parameter rows of ``## section``'s tables that state one: a quoted
    string followed by "(default", "-1 = the preset's value (default)" or "default <numbers>"."""
    text = DOC.read_text(encoding="utf-8").split(f"\n## {section}\n", 1)[1].split("\n## ", 1)[0]
    found = {}
    for line in text.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) != 3 or not cells[1].startswith("parameter"):
            continue
        names, meaning = re.findall(r"`(\w+)`", cells[0]), cells[2].replace("**", "").replace("−", "-")
        quoted = re.search(r'`"(\w+)"` \(default', meaning)
        numbers = re.search(r"\bdefault (-?[\d.]+(?:e-?\d+)?(?:, -?[\d.]+(?:e-?\d+)?)*)", meaning)
        if quoted:
            values = [quoted.group(1)] * len(names)
        elif "-1 = the preset's value (default)" in meaning:
            values = [-1.0] * len(names)
        elif numbers:
            values = [float(v) for v in numbers.group(1).split(", ")]
            values = values * len(names) if len(values) == 1 else values
        else:
            continue
        assert len(values) == len(names), line
        found.update(zip(names, values))
    return found


@pytest.mark.parametrize("model, least", [("DCMotorDrive", 14), ("CurrentObserver", 6)])
def test_each_documented_default_is_the_slaves_start(model, least):
    """Catches a parameter's declared start off the documented default (an observer estimating from a
    speed of 1 rad/s where the table says 0, a -1 sentinel replaced by a value) and the tables' rows
    no longer read (at least ``least`` defaults found)."""
    defaults = documented_defaults(model)
    assert len(defaults) >= least, defaults
    slave = getattr(importlib.import_module(f"fmus.slaves.{SLAVES[model]}"), model)(instance_name="m")
    declared = {name: getattr(slave, name) for name in defaults}
    assert declared == defaults
