"""scenarios/run/runner.py ``run_scene``'s files for a run with a single row (issue 31, session 44:
the plots' row-count boundary hit exactly): a refused initialisation records t = 0 only; its
out dir holds result.csv and metrics.json read back exactly, and no figure (a path needs two
points)."""
from __future__ import annotations

import csv
import json

from fmus.cosim.system import Component, System
from scenarios.run.runner import run_scene
from scenarios.scenes.scene import Scene


def _refused_at_start() -> Scene:
    """The bench plant started far off its workspace (x0 = 5 m): its initialisation refuses."""
    components = (Component("traj", "Trajectory", {"kind": "hold"}),
                  Component("ctrl", "PositionController", {"strategy": "PDx"}),
                  Component("plant", "FiveBarPlant", {"preset": "bench", "x0": 5.0, "y0": 0.108}))
    record = ("plant.x", "plant.y", "traj.x_d", "traj.y_d", "ctrl.tau1", "ctrl.tau2")
    system = System(components, (), record, stop_time=0.01)
    columns = dict(zip(("x", "y", "x_d", "y_d", "tau1", "tau2"), record))
    return Scene("refused_start", "refused at its start", system, columns, (0.0, 0.01), 0.01, "none")


def test_a_run_of_one_row_writes_its_csv_and_metrics_but_no_figure(tmp_path):
    """Plots asked for (the default), one row recorded: the files are the csv and the metrics
    only, the csv's one row at t = 0 and the metrics' outcome the refused initialisation.
    Catches the figures drawn from one row (``>=`` for ``>`` on the row count)."""
    outcome = run_scene(_refused_at_start(), out_dir=tmp_path)
    assert len(outcome.columns["t"]) == 1 and not outcome.result.interrupted
    assert [f.name for f in outcome.files] == ["result.csv", "metrics.json"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["metrics.json", "result.csv"]
    with open(tmp_path / "result.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 1 and float(rows[0]["t"]) == 0.0
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    assert metrics["error"]["instance"] == "plant" and metrics["error"]["time"] == 0.0
    assert metrics["simulated_s"] == 0.0 and metrics["completed"] is False


def test_the_error_message_is_the_records_message_the_old_text_itself_or_empty():
    """``error_message``: "" for a completed run (no ``error``, or null), the record's message,
    a metrics.json of before the record (its ``error`` the text) gives that text."""
    from scenarios.run.runner import error_message

    assert error_message({}) == "" and error_message({"error": None}) == ""
    assert error_message({"error": {"kind": "refused", "message": "plant: singular at t = 0.2 s"}}) == \
        "plant: singular at t = 0.2 s"
    assert error_message({"error": "drive1: refused"}) == "drive1: refused"
    assert error_message({"error": {"kind": "refused"}}) == ""


def test_a_completed_run_of_two_rows_or_more_writes_its_three_figures(tmp_path):
    """The other side of the row-count edge: bench_circle_PDq cut to 5 ms (6 rows), plots by
    default, completed: csv, metrics and the path, errors and torques figures.  Catches the
    figures' condition inverted on the interruption."""
    from dataclasses import replace

    from scenarios.scenes.catalogue import get_scene

    scene = get_scene("bench_circle_PDq")
    scene = replace(scene, system=replace(scene.system, stop_time=0.005))
    outcome = run_scene(scene, out_dir=tmp_path)
    assert outcome.result.completed and len(outcome.columns["t"]) == 6
    assert [f.name for f in outcome.files] == ["result.csv", "metrics.json", "path.png", "errors.png", "torques.png"]


def test_a_write_error_keeps_the_errors_errno_and_is_eio_without_one(tmp_path):
    """check_writable under a file: the OS's ENOTDIR, not a generic one; atomic_write's OSError
    without an errno: EIO, its text the reason.  Catches the errno replaced by EIO (``and`` for ``or``)."""
    import errno

    import pytest

    from scenarios.run import runner

    path = tmp_path / "f"
    path.write_text("x")
    with pytest.raises(runner.WriteError) as failure:
        runner.check_writable(path / "out")
    assert failure.value.errno == errno.ENOTDIR

    def broken(f):
        raise OSError("no errno here")

    with pytest.raises(runner.WriteError) as failure:
        runner.atomic_write(tmp_path / "m.json", broken)
    assert failure.value.errno == errno.EIO and failure.value.strerror == f"cannot write {tmp_path / 'm.json'}: no errno here"
