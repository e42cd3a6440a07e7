"""A strategy as a scene file gives it, for the tests of the control law."""
import dataclasses
import json

from controller.strategies import Strategy, get_strategy


def strategy_read_from_a_file(name: str) -> Strategy:
    """The preset strategy ``name`` with every field through JSON: its strings are new objects,
    equal to the literals "x", "q" but not the same objects (a law that compared by identity
    would take a task-space strategy read from a file for a joint-space one)."""
    fields = json.loads(json.dumps(dataclasses.asdict(get_strategy(name))))
    return Strategy(**{key: tuple(v) if isinstance(v, list) else v for key, v in fields.items()})
