"""The plant demo (scenarios/examples/plant_demo.py, ``parcosim demo``): its rows and its figure."""
from __future__ import annotations

import math

import numpy as np
import pytest

from scenarios.examples import plant_demo


def test_the_demo_starts_at_rest_at_7_17_with_the_briefs_joint_angles():
    """Row 0 is t = 0 at (0.07, 0.17) m (7.17) where SYSTEM.md section 2 gives q1 ≈ 24.36°,
    q2 ≈ 99.97° for Table 3; one row per 1 ms; the loop stays closed (residual < 1e-9 m).
    Catches a shifted start, a missing last row or another sample time."""
    rows = plant_demo.simulate(t_end=0.05)
    assert rows.shape == (51, 6)
    assert np.allclose(np.diff(rows[:, 0]), 1e-3, rtol=1e-9, atol=0.0) and rows[0, 0] == 0.0
    assert (rows[0, 1], rows[0, 2]) == pytest.approx((0.07, 0.17), abs=1e-12)
    assert (math.degrees(rows[0, 3]), math.degrees(rows[0, 4])) == pytest.approx((24.36, 99.97), abs=0.01)
    assert np.max(np.abs(rows[:, 5])) < 1e-9
    assert np.hypot(rows[-1, 1] - 0.07, rows[-1, 2] - 0.17) > 1e-5     # the torques moved it


def test_the_figure_draws_the_path_and_marks_its_start(tmp_path, monkeypatch):
    """The red path through every row's (x, y) and the start marker at row 0's (x, y).  Catches
    the start marker at a time/position mix-up (row 1's t as x)."""
    import matplotlib.pyplot as plt

    kept = []
    close = plt.close
    monkeypatch.setattr(plt, "close", lambda fig=None: kept.append(fig) or close(fig))
    rows = plant_demo.simulate(t_end=0.02)
    rows[:, 1] += np.linspace(0.0, 1e-3, len(rows))          # a path that visibly moves
    assert plant_demo.plot(rows, "thesis_sim", tmp_path / "demo.png") == tmp_path / "demo.png"
    lines = {line.get_label(): line for line in kept[0].axes[0].lines}
    path, start = lines["end-effector path"], lines["start"]
    assert np.array_equal(path.get_xdata(), rows[:, 1]) and np.array_equal(path.get_ydata(), rows[:, 2])
    assert (np.ravel(start.get_xdata())[0], np.ravel(start.get_ydata())[0]) == (rows[0, 1], rows[0, 2])


def test_the_demo_prints_every_50_ms_and_writes_its_figure(tmp_path, capsys):
    """``parcosim demo``'s table: a header, then t, x, y, q1 [deg], q2 [deg], residual every 50 ms
    from 0 to 0.5 s (11 rows, the simulated rows' values), then the PNG's path.  Catches rows at
    another stride, angles left in radians, columns swapped, the figure not written, and the
    output folder made without its missing parent (sibling of seed 4201 [196])."""
    path = plant_demo.run(tmp_path / "new" / "out")
    assert path == tmp_path / "new" / "out" / "plant_demo.png" and path.read_bytes()[:4] == b"\x89PNG"
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].split() == ["t", "[s]", "x", "[m]", "y", "[m]", "q1", "[deg]", "q2", "[deg]", "residual", "[m]"]
    assert lines[-1] == f"wrote {path}" and len(lines) == 13
    rows = plant_demo.simulate()
    for line, k in zip(lines[1:-1], range(0, 501, 50)):
        t, x, y, q1, q2, res = (float(v) for v in line.split())
        assert t == pytest.approx(k * 1e-3, abs=5e-4)
        assert (x, y) == pytest.approx((rows[k, 1], rows[k, 2]), abs=6e-6)
        assert (q1, q2) == pytest.approx((math.degrees(rows[k, 3]), math.degrees(rows[k, 4])), abs=6e-4)
        assert abs(res - rows[k, 5]) <= 1e-2 * abs(rows[k, 5]) + 1e-300


def test_the_demo_steps_the_plant_with_its_documented_torques_from_the_start_of_each_step():
    """torques(t) is the docstring's τ1 = 0.03 sin(2π 2 t), τ2 = -0.03 sin(2π 3 t) N m, and
    simulate's rows are those of a PlantSimulator stepped here with that profile at each step's
    start time.  Catches a torque's sign, amplitude or frequency changed, the torques swapped or
    taken at the end of the step, another preset or start point."""
    from plant import PlantSimulator, get_preset

    for t in (0.0, 0.05, 0.1, 0.125, 0.3, 0.49):
        assert plant_demo.torques(t) == pytest.approx(
            (0.03 * math.sin(4 * math.pi * t), -0.03 * math.sin(6 * math.pi * t)), rel=1e-12, abs=1e-15)
    rows = plant_demo.simulate(t_end=0.06)
    sim = PlantSimulator(get_preset("thesis_sim"), 0.07, 0.17)
    for k in range(60):
        t = k * 1e-3
        sim.step(0.03 * math.sin(4 * math.pi * t), -0.03 * math.sin(6 * math.pi * t), 1e-3)
    out = sim.outputs()
    assert rows[-1, 1:5] == pytest.approx([out["x"], out["y"], out["q1"], out["q2"]], rel=1e-12, abs=1e-15)


def test_the_demo_steps_the_plant_once_per_interval_and_never_past_its_last_row(monkeypatch):
    """0.05 s at 1 ms: 51 rows, 50 steps, each from the time of the row before; no step after
    the last row (its state would be thrown away, and a step failing there would fail a demo whose
    rows were all made).  Training sample 4203 [15]: a 51st step went unseen."""
    from plant import PlantSimulator

    times = []

    class Counted(PlantSimulator):
        def step(self, *args):
            times.append(self.time)
            return super().step(*args)

    monkeypatch.setattr(plant_demo, "PlantSimulator", Counted)
    rows = plant_demo.simulate(t_end=0.05)
    assert len(rows) == 51 and len(times) == 50
    assert times == pytest.approx(list(rows[:-1, 0]), abs=1e-15)
