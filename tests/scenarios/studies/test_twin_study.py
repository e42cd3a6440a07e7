"""scenarios/studies/twin_fit.py's study drivers without their runs (``run_twin`` replaced by one
that records what it is asked and gives metrics computed from it): the prediction's kinds and
seeds, the sensitivity's relative steps of friction_scale on one seed and one strategy at a
time and its table in twin.md, the report's files (twin_runs.json read back exactly, twin.md
ending with the link to the method), and the command's options (issue 31: options taking
effect, every written value read back; these functions were run by no test)."""
from __future__ import annotations

import json

import numpy as np

import pytest

from scenarios.studies import twin_fit
from tests.support.paths import ROOT


@pytest.fixture
def asked(monkeypatch):
    """run_twin: e_ef = 10 friction_scale + the seed / 1000, per strategy index; records calls."""
    calls = []

    def run_twin(twin, kind, seeds=twin_fit.SPREAD_SEEDS, strategies=twin_fit.ORDER):
        calls.append((twin.friction_scale, kind, tuple(seeds), tuple(strategies)))
        return {s: {seed: {"e_ef_mm": 10 * twin.friction_scale + seed / 1000 + twin_fit.ORDER.index(s),
                           "tau_ef_Nm": 0.5, "e_ss_mm": 0.25 * twin.friction_scale + (kind == "triangle"),
                           "settled": True, "t_settle_s": 1.5, "e_ss_1s_mm": 0.75, "completed": True,
                           "e_contour_sides_mm": [0.1, 0.2, 0.3], "wall_s": 9.0}
                    for seed in seeds} for s in strategies}

    monkeypatch.setattr(twin_fit, "run_twin", run_twin)
    return calls


def test_the_prediction_runs_both_kinds_on_the_seeds_given(asked):
    """Catches a kind left out, the seeds not passed, and another twin run."""
    twin = twin_fit.START
    runs = twin_fit.predict(twin, seeds=(7, 9))
    assert asked == [(twin.friction_scale, "circle", (7, 9), twin_fit.ORDER),
                     (twin.friction_scale, "triangle", (7, 9), twin_fit.ORDER)]
    assert list(runs) == ["circle", "triangle"] and list(runs["triangle"]["TCx"]) == [7, 9]


def test_the_sensitivity_moves_friction_scale_by_each_relative_step_on_the_first_spread_seed(asked):
    """Catches an absolute step (or one of another sign), another parameter moved, a run of
    every strategy or seed at each step, and a step's metrics filed under another."""
    twin = twin_fit.START
    moved = twin_fit.sensitivity(twin)
    assert len(asked) == 2 * 8 * len(twin_fit.SENSITIVITY_STEPS)
    first = twin_fit.SPREAD_SEEDS[0]
    for scale, kind, seeds, strategies in asked:
        assert seeds == (first,) and len(strategies) == 1 and kind in ("circle", "triangle")
    for kind in ("circle", "triangle"):
        for s in twin_fit.ORDER:
            assert list(moved[kind][s]) == list(twin_fit.SENSITIVITY_STEPS)
            for step, m in moved[kind][s].items():
                scale = twin.friction_scale * (1 + step)
                assert m["e_ef_mm"] == pytest.approx(10 * scale + first / 1000 + twin_fit.ORDER.index(s), rel=1e-15)
                assert m["e_ss_mm"] == pytest.approx(0.25 * scale + (kind == "triangle"), rel=1e-15)
    assert twin_fit.SENSITIVITY_STEPS == (-2e-3, -1e-3, 1e-3, 2e-3)


def test_the_sensitivity_table_gives_the_seed_mean_beside_the_range_over_the_steps(asked):
    """Catches the fitted value or the range of another metric, kind or statistic."""
    twin = twin_fit.START
    runs, moved = twin_fit.predict(twin, seeds=(1, 2, 3)), twin_fit.sensitivity(twin)
    lines = twin_fit.render(runs, twin, {"loss": 0.5, "start_loss": 1.0, "evaluations": 3, "seeds": [1]},
                            moved).splitlines()
    heading = (f"## Sensitivity: friction_scale × (1 + step), step in {list(twin_fit.SENSITIVITY_STEPS)}, seed "
               f"{twin_fit.SPREAD_SEEDS[0]}")
    at = lines.index(heading)
    f, first = twin.friction_scale, twin_fit.SPREAD_SEEDS[0]
    low, high = f * (1 - 2e-3), f * (1 + 2e-3)
    for k, s in enumerate(twin_fit.ORDER):
        cells = []
        for kind in ("circle", "triangle"):
            e_ef = (10 * f + 0.002 + k, 10 * low + first / 1000 + k, 10 * high + first / 1000 + k)
            e_ss = tuple(0.25 * x + (kind == "triangle") for x in (f, low, high))
            cells += [f"{a:.3f} [{b:.3f}–{c:.3f}]" for a, b, c in (e_ef, e_ss)]
        assert f"| {s} | " + " | ".join(cells) + " |" in lines[at:], s


def test_the_report_writes_every_runs_metrics_the_figure_and_twin_md_ending_with_the_method(asked, monkeypatch,
                                                                                              tmp_path):
    """Catches a kept metric left out of twin_runs.json (or another's value), the figure not
    drawn into the folder, and twin.md not the rendered tables, the figure and the link."""
    drawn = []
    monkeypatch.setattr(twin_fit, "load_twin", lambda: twin_fit.START)
    monkeypatch.setattr(twin_fit, "read_fit", lambda: {"loss": 0.5, "start_loss": 1.0, "evaluations": 3,
                                                       "seeds": [1]})
    monkeypatch.setattr(twin_fit, "calibration_spread", lambda info: [])
    monkeypatch.setattr(twin_fit, "plot", lambda runs, path: drawn.append(path) or path)
    path = twin_fit.write_twin_report(tmp_path / "twin", seeds=(4, 5))
    assert path == tmp_path / "twin" / "twin.md" and drawn == [tmp_path / "twin" / "twin.png"]
    runs = twin_fit.predict(twin_fit.START, (4, 5))
    back = json.loads((tmp_path / "twin" / "twin_runs.json").read_text())
    assert back == {kind: {s: {str(seed): {k: v for k, v in m.items() if k != "wall_s"} for seed, m in by.items()}
                           for s, by in runs[kind].items()} for kind in runs}
    text = path.read_text()
    moved = twin_fit.sensitivity(twin_fit.START)
    assert text == (twin_fit.render(runs, twin_fit.START, twin_fit.read_fit(), moved, [])
                    + "![twin beside the bench](twin.png)\n\n" + twin_fit.METHOD_LINK)


@pytest.fixture
def command(monkeypatch):
    calls = []
    monkeypatch.setattr(twin_fit, "fit", lambda points, starts, maxfev, workers: calls.append(
        ("fit", points, starts, maxfev, workers)) or twin_fit.START)
    monkeypatch.setattr(twin_fit, "write_twin_report", lambda out: calls.append(("report", out)) or out)
    return calls


def test_the_command_fits_reports_or_both_with_its_options(command, capsys):
    """Catches an option not passed to the fit (or to the wrong parameter), ``--docs`` not the
    repository's docs/, ``--out`` ignored, and "fit" or "report" running the other too."""
    assert twin_fit.main(["fit", "--points", "8", "--starts", "3", "--maxfev", "30", "--workers", "5"]) == 0
    assert command == [("fit", 8, 3, 30, 5)]
    assert capsys.readouterr().out == f"fitted: {twin_fit.START.values()}\n"
    command.clear()
    assert twin_fit.main(["report", "--out", "x/y"]) == 0 and command == [("report", "x/y")]
    command.clear()
    assert twin_fit.main(["report", "--docs", "--out", "x/y"]) == 0 and command == [("report", str(ROOT / "docs"))]
    command.clear()
    assert twin_fit.main([]) == 0 and command == [("fit", 64, 4, 120, 2), ("report", "out/twin")]


def test_the_descents_first_simplex_steps_each_parameter_inwards_by_a_tenth_of_its_range(monkeypatch):
    """The first evaluations of a descent are its start and the start moved by
    :data:`SIMPLEX_STEP` of one parameter's range, up, or down where up would leave the box
    (a parameter at 0.95 or 1 of its range).  Catches a step outwards (clipped to the bound: a
    degenerate simplex), the step of another size or on another parameter."""
    seen = []

    def evaluate(u, seeds):
        seen.append(np.array(u, dtype=float))
        return float(np.sum((np.asarray(u) - 0.3) ** 2)), twin_fit._from_unit(u)

    monkeypatch.setattr(twin_fit, "evaluate", evaluate)
    n = len(twin_fit.PARAMETERS)
    u0 = np.linspace(0.2, 1.0, n)
    u0[0] = 0.95
    start = twin_fit._from_unit(u0)
    twin_fit.descend(start, maxfev=n + 1, log=lambda line: None)
    first = twin_fit._to_unit(start)
    np.testing.assert_allclose(seen[0], first, atol=1e-12)
    for i in range(n):
        step = twin_fit.SIMPLEX_STEP if first[i] < 1 - twin_fit.SIMPLEX_STEP else -twin_fit.SIMPLEX_STEP
        expected = first.copy()
        expected[i] += step
        np.testing.assert_allclose(seen[i + 1], expected, atol=1e-12)
    assert sum(first >= 1 - twin_fit.SIMPLEX_STEP) >= 2
