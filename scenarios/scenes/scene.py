"""What a scene is: a co-simulation system plus what its metrics need (thesis 7.31-7.32).

Every scene module builds :class:`Scene` objects (:mod:`scenarios.scenes.thesis`,
:mod:`scenarios.scenes.pendulum`, :mod:`scenarios.scenes.twin`); :mod:`scenarios.scenes.catalogue`
names them.
"""
from __future__ import annotations

from dataclasses import dataclass

from fmus.cosim.system import System

#: Time the bench scenes run on after the reference stops, for the steady-state error [s]:
#: the slowest of the 16 bench scenes (bench_triangle_PDMDq) settles 1.9 s after the stop
#: (docs/twin_method.md "Settled steady-state error"), and :data:`scenarios.run.metrics.SETTLE_HOLD`
#: must follow.
SETTLE_TIME = 3.0
#: The final position (the settling band's centre) is the mean over this last part of the run [s].
STEADY_STATE_WINDOW = 0.2


@dataclass(frozen=True)
class Scene:
    """A runnable scene.

    Parameters
    ----------
    name, description : str
    system : System
    columns : dict
        Result column -> recorded signal ("instance.variable"); the contract's
        columns ``x, y, x_d, y_d, tau1, tau2`` are always there.
    window : (float, float)
        Time window of e_ef and tau_ef (7.31-7.32) [s].
    reference_end : float
        When the reference stops moving [s]; the steady-state error is measured after it,
        once the end effector settled (:mod:`scenarios.run.metrics`).
    strategy : str
    """

    name: str
    description: str
    system: System
    columns: dict
    window: tuple
    reference_end: float
    strategy: str
