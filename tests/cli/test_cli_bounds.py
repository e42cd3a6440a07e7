"""Every bounded integer option of every ``parcosim`` command at its bound and one below it: the
least value taken as given, one less refused in one line naming the option and the text
(issue 31: the options' bounds ran only through a few whole commands, never at their edges; a
bound off by one, or one option's bound given to another, passed every test)."""
from __future__ import annotations

import pytest

from parcosim import cli
from parcosim.checks import CommandError

#: command -> the arguments it needs besides the option tested.
NEEDS = {"run": ["run", "s"], "report": ["report"], "export-ssp": ["export-ssp", "s", "p.ssp"],
         "export-fmu": ["export-fmu", "s", "p.fmu"],
         "sweep": ["sweep", "s", "--samples", "3", "--uncertainty", "0.1"]}
#: (command, option, least, the name its refusal gives), from docs/index.md: a retry splits a
#: step in N >= 2 sub-steps; counts of workers, samples and RK4 steps start at 1; seeds at 0.
BOUNDS = [("run", "--retry-substeps", 2, "retry_substeps"), ("run", "--drives-in-plant", 1, "--drives-in-plant"),
          ("report", "--workers", 1, "--workers"), ("sweep", "--samples", 1, "--samples"),
          ("sweep", "--seed", 0, "--seed"), ("sweep", "--workers", 1, "--workers"),
          ("export-ssp", "--drives-in-plant", 1, "--drives-in-plant"),
          ("export-fmu", "--drives-in-plant", 1, "--drives-in-plant")]


def _bounded_options() -> set:
    """(command, option) of every option of the parser whose type is ``at_least``."""
    parser = cli._parser()
    commands = next(a for a in parser._actions if a.dest == "command").choices
    return {(name, action.option_strings[0]) for name, sub in commands.items() for action in sub._actions
            if action.option_strings and getattr(action.type, "__qualname__", "").startswith("at_least")}


def test_the_table_lists_every_bounded_option():
    """Catches an option whose bound this file does not hold (a new one, or one renamed)."""
    assert _bounded_options() == {(command, option) for command, option, _, _ in BOUNDS}


@pytest.mark.parametrize("command, option, least, name", BOUNDS)
def test_each_bounded_option_takes_its_least_value_and_refuses_one_less(command, option, least, name):
    """Catches a bound off by one or moved (``--workers 1`` refused, ``--seed -1`` taken), and a
    refusal without the option, the text given or the bound."""
    dest = option.lstrip("-").replace("-", "_")
    for value in (least, least + 1, least + 10):
        args = cli._parser().parse_args(NEEDS[command] + [option, str(value)])
        assert getattr(args, dest) == value and type(getattr(args, dest)) is int
    with pytest.raises(CommandError) as refused:
        cli._parser().parse_args(NEEDS[command] + [option, str(least - 1)])
    assert str(refused.value) == (f"argument {option}: {name} = {least - 1} must be an integer >= {least} "
                                  f"(`parcosim {command} --help` lists the options)")
