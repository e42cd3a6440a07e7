"""A co-simulation system as plain data: components, connections, recorded signals.

The same :class:`System` is run by :mod:`fmus.cosim.master` (either back end) and
written to SSP by :mod:`fmus.ssp.export`.  Signals are named ``"instance.variable"``.
"""
from __future__ import annotations

from dataclasses import dataclass, field

#: The thesis' sample time (7.2): the communication step of every scene [s].
SAMPLE_TIME = 1e-3


@dataclass(frozen=True)
class Component:
    """One FMU instance.

    Parameters
    ----------
    name : str
        Instance name (unique in the system).
    model : str
        FMU model name, one of :data:`fmus.export.build.SLAVES` (``FiveBarPlant``, ...).
    parameters : dict
        Parameter name -> value (float, int, bool or str), set during initialisation.
    substeps : int
        Multi-rate: the master calls ``doStep`` this many times per communication
        step, with inputs held, each step ``h / substeps`` long.
    """

    name: str
    model: str
    parameters: dict = field(default_factory=dict)
    substeps: int = 1

    def __post_init__(self):
        if not self.name or "." in self.name:
            raise ValueError(f"component name {self.name!r} must be non-empty and contain no '.'")
        if not (isinstance(self.substeps, int) and self.substeps >= 1):
            raise ValueError(f"component {self.name}: substeps = {self.substeps!r} must be an integer >= 1")


@dataclass(frozen=True)
class Connection:
    """Output ``source`` ("instance.variable") drives input ``target``."""

    source: str
    target: str


def split_signal(signal: str) -> tuple[str, str]:
    """``"plant.x"`` -> ``("plant", "x")``; a clear error for anything else."""
    instance, dot, variable = signal.partition(".")
    if not dot or not instance or not variable:
        raise ValueError(f"signal {signal!r} must be written 'instance.variable'")
    return instance, variable


@dataclass(frozen=True)
class System:
    """Components, their connections, and what to record, run at a fixed step.

    Parameters
    ----------
    components : tuple of Component
        In the order a reader expects (signal flow); the master derives its own
        stepping order from the connections and uses this order only to break ties.
    connections : tuple of Connection
        Every connected input; unconnected inputs keep their start values.
    record : tuple of str
        Signals recorded at every communication point, "instance.variable";
        each one is a column of the result, named by the signal.
    stop_time : float
        End of the run [s]; the run starts at 0.
    step : float
        Communication step [s] (the thesis' 1 ms sample time by default).
    """

    components: tuple
    connections: tuple
    record: tuple
    stop_time: float
    step: float = SAMPLE_TIME

    def __post_init__(self):
        names = [c.name for c in self.components]
        duplicates = {n for n in names if names.count(n) > 1}
        if duplicates:
            raise ValueError(f"duplicate component names: {sorted(duplicates)}")
        if not self.step > 0.0:
            raise ValueError(f"step = {self.step!r} s must be > 0")
        if not self.stop_time >= 0.0:
            raise ValueError(f"stop_time = {self.stop_time!r} s must be >= 0")
        targets = [c.target for c in self.connections]
        for target in targets:
            if targets.count(target) > 1:
                raise ValueError(f"input {target} is connected more than once")
        for signal in [s for c in self.connections for s in (c.source, c.target)] + list(self.record):
            instance, _ = split_signal(signal)
            if instance not in names:
                raise ValueError(f"signal {signal!r} names no component (components: {', '.join(names)})")

    def component(self, name: str) -> Component:
        """The component called ``name``."""
        for c in self.components:
            if c.name == name:
                return c
        raise KeyError(name)

    @property
    def steps(self) -> int:
        """Number of communication steps from 0 to stop_time."""
        return int(round(self.stop_time / self.step))
