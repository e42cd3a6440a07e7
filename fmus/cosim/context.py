"""What one run of :func:`fmus.cosim.master.simulate` is given (:class:`RunContext`) and what its
loop hands back (:class:`Outcome`): one record each, passed whole to the functions that load,
initialise and step the system (in Python, :mod:`fmus.cosim.master`; compiled,
:mod:`fmus.cosim.compiled`) instead of the same arguments one by one."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from fmus.cosim.system import System


class NoInterrupt:
    """An interrupt flag that is never raised (:func:`fmus.cosim.master.deferred_sigint` gives the real one)."""

    requested = False


@dataclass(frozen=True)
class RunContext:
    """One run's settings, as :func:`fmus.cosim.master.simulate` checked them.

    ``system`` is the system as run (parameters a foreign FMU lacks left out); ``interrupt``
    has ``requested``, set by a SIGINT; ``progress(fraction)`` is called about a hundred times.
    """

    system: System
    mode: str
    coupling: str = "gauss-seidel"
    fmu_dir: object = None
    progress: Callable | None = None
    retry_substeps: int | None = None
    interrupt: object = NoInterrupt


@dataclass
class Outcome:
    """What stepping produced: the rows recorded (row 0 after initialisation), the refusal
    that stopped it (a :class:`fmus.cosim.backends.CoSimulationError`) or None, whether a
    SIGINT stopped it, the stepping's wall time, the initialisation's, and the mode's extras."""

    rows: np.ndarray
    error: Exception | None = None
    interrupted: bool = False
    wall_s: float = 0.0
    init_s: float = 0.0
    extra: dict = field(default_factory=dict)
