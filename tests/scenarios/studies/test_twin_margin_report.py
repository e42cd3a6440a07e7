"""scenarios/studies/twin_margin.py without its compiled runs (``run_scene`` replaced by one that
records each scene and gives made-up signals): each row's scenes at λ and λ + extra with the
delay and cut-off asked for, the peak drive voltage over both drives, the table's cells read
back, an unknown kind refused, and the command's options reaching ``margin`` (issue 31: options
taking effect, every printed value read back; the module's runs are in a slow test)."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from scenarios.scenes.twin import Twin
from scenarios.studies import twin_margin


@pytest.fixture
def runs(monkeypatch):
    """run_scene: drive 1 peaks at -(λ / 10) V, drive 2 at +3 V; e_ef = λ / 100 mm."""
    seen = []

    def run_scene(scene, mode, plots):
        ctrl = scene.system.component("ctrl").parameters
        seen.append((mode, plots, ctrl["lam"], ctrl["delay_steps"], scene.system.component("deriv").parameters))
        signals = {"drive1.v": np.array([0.5, -ctrl["lam"] / 10, 1.0]), "drive2.v": np.array([3.0, -2.0, 0.0])}
        metrics = {"e_ef_mm": ctrl["lam"] / 100, "tau_ef_Nm": 0.125, "e_max_mm": 2.5}
        return SimpleNamespace(result=SimpleNamespace(signals=signals), metrics=metrics)

    monkeypatch.setattr(twin_margin, "run_scene", run_scene)
    return seen


def test_each_row_runs_the_tables_lambda_and_the_raised_one_with_the_delay_and_cut_off(runs):
    """Catches the raise not added (or added to the base run), the delay or the cut-off not
    reaching the scene, a run not compiled or drawing figures, and the peak voltage of one
    drive or signed."""
    rows = twin_margin.margin("circle", 7.5, delays=(2, 4), twin=Twin(), strategies=("TCq", "PDx"), fc_vel=80.0)
    lams = {s: twin_margin.get_strategy(s, "circle").lam for s in ("TCq", "PDx")}
    assert [(r["delay"], r["strategy"], r["lam"]) for r in rows] == [
        (2, "TCq", lams["TCq"]), (2, "PDx", lams["PDx"]), (4, "TCq", lams["TCq"]), (4, "PDx", lams["PDx"])]
    assert [(mode, plots, lam, delay) for mode, plots, lam, delay, _ in runs] == [
        ("compiled", False, lam, delay) for delay in (2, 4) for s in ("TCq", "PDx")
        for lam in (lams[s], lams[s] + 7.5)]
    assert {deriv["fc_vel"] for *_, deriv in runs} == {80.0}
    for r in rows:
        assert r["base"]["v_peak"] == max(r["lam"] / 10, 3.0) and r["raised"]["e_ef_mm"] == (r["lam"] + 7.5) / 100
    default = twin_margin.margin("triangle", twin=Twin(), strategies=("PDq",))[0]
    assert default["delay"] == twin_margin.DELAY_STEPS and runs[-1][3] == twin_margin.DELAY_STEPS
    assert runs[-1][4].get("fc_vel") != 80.0          # no cut-off asked: the scene's own
    assert default["raised"]["e_ef_mm"] == pytest.approx((default["lam"] + twin_margin.THESIS_LAMBDA_STEP) / 100)


def test_an_unknown_kind_is_refused_naming_the_valid_ones(runs):
    with pytest.raises(ValueError, match=r"^kind = 'square'; valid: circle, triangle$"):
        twin_margin.margin("square")
    assert runs == []


def test_the_table_gives_each_rows_base_and_raised_metrics_to_their_digits():
    """Catches a cell of the other run, another metric or other digits, and the header's λ step."""
    rows = [{"delay": 3, "strategy": "TCx", "lam": 60.0,
             "base": {"e_ef_mm": 1.234, "tau_ef_Nm": 0.1234, "e_max_mm": 5.55, "v_peak": 12.34},
             "raised": {"e_ef_mm": 2.345, "tau_ef_Nm": 0.2345, "e_max_mm": 6.66, "v_peak": 23.45}}]
    lines = twin_margin.render(rows, 2.5).splitlines()
    assert lines[0].startswith("| delay [samples] | strategy | λ | e_ef mm at λ | at λ+2.5 |") and len(lines) == 3
    assert lines[2] == "| 3 | TCx | 60 | 1.23 | 2.35 | 0.123 | 0.234 | 5.5 | 6.7 | 12.3 | 23.4 |"


def test_the_command_passes_its_options_to_margin_and_prints_the_table(monkeypatch, capsys):
    """Catches --kind, --extra, --delays or --fc-vel not reaching ``margin`` or reaching another
    parameter, the table rendered with another step, and its last line without a newline."""
    asked = []
    rows = [{"delay": 1, "strategy": "PDq", "lam": 35.0,
             "base": {"e_ef_mm": 1.0, "tau_ef_Nm": 0.1, "e_max_mm": 2.0, "v_peak": 3.0},
             "raised": {"e_ef_mm": 1.5, "tau_ef_Nm": 0.2, "e_max_mm": 4.0, "v_peak": 6.0}}]
    monkeypatch.setattr(twin_margin, "margin", lambda *a, **kw: asked.append((a, kw)) or rows)
    assert twin_margin.main(["--kind", "triangle", "--extra", "2.5", "--delays", "1", "6", "--fc-vel", "40"]) == 0
    assert asked == [(("triangle", 2.5, [1, 6]), {"fc_vel": 40.0})]
    out = capsys.readouterr().out
    assert out == twin_margin.render(rows, 2.5)
    # printed with end="": the table itself ends its last row, so the shell's prompt starts a line
    assert out.endswith(" |\n") and out.count("\n") == 3
    asked.clear()
    twin_margin.main([])
    assert asked == [(("circle", twin_margin.THESIS_LAMBDA_STEP, [twin_margin.DELAY_STEPS]), {"fc_vel": None})]


def test_the_twin_given_is_the_one_run_and_none_runs_the_shipped_one(monkeypatch):
    """Each run's drives carry the twin asked for (μ = friction_scale x the preset's, μs =
    stiction_ratio x μ, ωs = stribeck_speed) and its plant bench_real's for that twin; with no
    twin, the shipped calibration's (load_twin).  Catches the twin argument ignored or the
    shipped file read in its place."""
    from motor import get_motor_preset
    from scenarios.scenes.twin import bench_real, load_twin

    scenes = []
    monkeypatch.setattr(twin_margin, "run_scene", lambda scene, mode, plots: scenes.append(scene) or SimpleNamespace(
        result=SimpleNamespace(signals={"drive1.v": np.zeros(2), "drive2.v": np.zeros(2)}), metrics={}))
    shipped = load_twin()
    twin = Twin(friction_scale=2.5, stiction_ratio=1.75, stribeck_speed=0.0625, current_offset=-0.125,
                current_noise=0.03125, inertia_error=0.25)
    assert twin != shipped
    for given, used in ((twin, twin), (None, shipped)):
        scenes.clear()
        twin_margin.margin("circle", twin=given, strategies=("PDx",))
        assert len(scenes) == 2
        plant = bench_real("PDx", "circle", used).system.component("plant").parameters
        for scene in scenes:
            assert scene.system.component("plant").parameters == plant
            for j in (1, 2):
                drive = scene.system.component(f"drive{j}").parameters
                mu = used.friction_scale * get_motor_preset(drive["preset"]).mu
                assert (drive["mu"], drive["mu_s"], drive["omega_s"]) == pytest.approx(
                    (mu, used.stiction_ratio * mu, used.stribeck_speed), rel=1e-15)
