"""Every ``python -m`` command of scenarios/ whose parser describes it by its docstring: its ``--help``
exits 0 and gives the first line of its module's docstring and, when it names itself, ``python -m
<module>`` as its program (issue 31: what a command prints read back)."""
from __future__ import annotations

import importlib
import sys

import pytest

#: The modules whose command describes itself with its docstring's first line.
DOCSTRING_COMMANDS = ("scenarios.batch.regression", "scenarios.examples.accurate_bench",
                      "scenarios.examples.plot_derivators", "scenarios.studies.balancing",
                      "scenarios.studies.pendulum_trade", "scenarios.studies.robustness",
                      "scenarios.studies.tools", "scenarios.studies.twin_fit", "scenarios.studies.twin_margin")


def _help(module, monkeypatch, capsys) -> str:
    monkeypatch.setenv("COLUMNS", "100")
    monkeypatch.setattr(sys, "argv", [module.__name__, "--help"])
    with pytest.raises(SystemExit) as done:
        module.main() if module.__name__.endswith("plot_derivators") else module.main(["--help"])
    assert done.value.code == 0
    return capsys.readouterr().out


@pytest.mark.parametrize("name", DOCSTRING_COMMANDS)
def test_help_gives_the_docstrings_first_line(name, monkeypatch, capsys):
    """Catches a command described by another line of its docstring (or none), another module's
    name as its program, or a command whose ``--help`` does not exit cleanly."""
    module = importlib.import_module(name)
    out = _help(module, monkeypatch, capsys)
    first = module.__doc__.splitlines()[0]
    assert out.startswith("usage: ")
    words = " ".join(out.split())
    assert " " + " ".join(first.split()) + " " in words, (first, out)
    prog = f"python -m {name}"
    if prog in out:                                     # the commands that name themselves say how to run them
        assert out.startswith(f"usage: {prog} ")
