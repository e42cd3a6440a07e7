"""scenarios/studies/tools.py at its edges, hit exactly, without a tool (issue 31, session 44:
boundaries of the generalised training sample): a tool's row within 1e-6 of a period of the
communication point is that point's row (inclusive), and a scene has drives when it has both."""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np

from scenarios.scenes.catalogue import get_scene
from scenarios.studies import tools

SCENE = get_scene("bench_circle_PDq")
PERIOD = 2.0 ** -10          # 1e-6 of it is exact to add to 0


def _metrics(times, x):
    times = np.asarray(times, dtype=float)
    n = len(times)
    signals = {"p.x": np.asarray(x, dtype=float), "p.y": np.full(n, 0.1), "t.x_d": np.zeros(n),
               "t.y_d": np.full(n, 0.1), "c.tau1": np.zeros(n), "c.tau2": np.zeros(n)}
    run = type("Run", (), {"time": times, "wall_s": 1.0, "error": None,
                           "__getitem__": lambda self, s: signals[s]})()
    columns = {"p.x": "x", "p.y": "y", "t.x_d": "x_d", "t.y_d": "y_d", "c.tau1": "tau1", "c.tau2": "tau2"}
    return tools.tool_metrics(SCENE, run, columns, period=PERIOD)


def test_a_row_exactly_1e_6_of_a_period_off_a_communication_point_is_its_row():
    """Rows at 0 + 1e-6 T and at T are kept (their errors, 3 mm and 1 mm, make e_max 3 mm); a
    row one float later than 1e-6 T is not (e_max 1 mm).  Catches ``<`` for ``<=``."""
    edge = 1e-6 * PERIOD
    assert abs(edge - 0 * PERIOD) == 1e-6 * PERIOD
    assert _metrics([edge, PERIOD], [3e-3, 1e-3])["e_max_mm"] == 3.0
    assert _metrics([math.nextafter(edge, 1.0), PERIOD], [3e-3, 1e-3])["e_max_mm"] == 1.0


def test_a_scene_has_drives_when_it_has_both_drive_instances_even_alone():
    """``{"drive1", "drive2"} <= names``: both present (with or without other components)."""
    def named(*names):
        return SimpleNamespace(system=SimpleNamespace(components=[SimpleNamespace(name=n) for n in names]))

    assert tools._has_drives(named("drive1", "drive2")) and tools._has_drives(named("plant", "drive2", "drive1"))
    assert not tools._has_drives(named("drive1", "plant")) and tools._has_drives(SCENE)


def test_a_run_whose_last_row_is_exactly_1e_6_s_before_the_stop_reached_it():
    """``completed`` needs the tool's last row at the stop time up to 1e-6 s, inclusive: a last row
    at exactly stop - 1e-6 completed, one a float earlier did not.  Catches ``>`` for ``>=``."""
    stop = SCENE.system.stop_time
    edge = stop - 1e-6
    assert _metrics([0.0, PERIOD, edge], [0.0, 0.0, 0.0])["completed"] is True
    assert _metrics([0.0, PERIOD, math.nextafter(edge, 0.0)], [0.0, 0.0, 0.0])["completed"] is False
