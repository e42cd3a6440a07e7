"""scenarios/examples/accurate_bench.py, the example README.md names, run for real on 20 ms of
a bench scene: both variants against the reference, each printed deviation and encoder count
read back against ``deviation`` and ``encoder_differences`` of runs made here, and its options
(scene, --stop-time, --substeps) taking effect (issue 31: a script no test ran; options and
printed values read back)."""
from __future__ import annotations

import re
from dataclasses import replace

import pytest

from fmus.cosim.master import simulate
from scenarios.examples import accurate_bench
from scenarios.reference import deviation, encoder_differences, reference_run
from scenarios.scenes.catalogue import get_scene
from scenarios.scenes.transforms import drives_in_plant

STOP = 0.02


def test_the_example_prints_each_variants_deviation_from_the_reference(capsys):
    """Catches a variant not run, the drives-in-plant variant at another substep count, the
    stop time not applied, and a printed deviation or encoder count of another run."""
    assert accurate_bench.main(["bench_circle_PDq", "--stop-time", str(STOP), "--substeps", "4"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == 3 and lines[0].startswith(f"bench_circle_PDq, 0-{STOP:g} s: reference (DOP853, rtol 1e-10) ")
    scene = get_scene("bench_circle_PDq")
    scene = replace(scene, system=replace(scene.system, stop_time=STOP))
    reference = reference_run(scene)
    record = ("plant.q1_enc", "plant.q2_enc")
    for line, label, variant in zip(lines[1:], ("separate drives (the scene)", "drives in plant, RK4 x4"),
                                    (scene, drives_in_plant(scene, substeps=4))):
        result = simulate(replace(variant.system, record=tuple(dict.fromkeys(variant.system.record + record))))
        assert result.completed and result.time[-1] == pytest.approx(STOP)
        d = deviation(result, reference)
        assert line.startswith(f"  {label:<32s} RMS {d['rms']:.2e} m, max {d['max']:.2e} m, "
                               f"{encoder_differences(result, reference)[0]} encoder differences, "), line
        assert re.search(r", [0-9.]+ s$", line)


def test_the_options_reach_the_scene_and_the_variant(monkeypatch, capsys):
    """Made-up runs: catches the scene argument, --stop-time or --substeps not used, and the
    defaults not the docstring's (bench_circle_TCMDx, 2 s, 8 substeps)."""
    asked = []

    class _Run:
        wall_s = 0.5

    monkeypatch.setattr(accurate_bench, "reference_run", lambda scene: asked.append(
        ("reference", scene.name, scene.system.stop_time)) or _Run())
    monkeypatch.setattr(accurate_bench, "drives_in_plant", lambda scene, substeps: asked.append(
        ("drives_in_plant", substeps)) or scene)
    monkeypatch.setattr(accurate_bench, "simulate", lambda system: asked.append(("simulate", system.stop_time,
                                                                               system.record[-2:])) or _Run())
    monkeypatch.setattr(accurate_bench, "deviation", lambda result, reference: {"rms": 1e-6, "max": 2e-6})
    monkeypatch.setattr(accurate_bench, "encoder_differences", lambda result, reference: (3, 0.1))
    accurate_bench.main([])
    assert asked == [("reference", "bench_circle_TCMDx", 2.0), ("drives_in_plant", 8),
                     ("simulate", 2.0, ("plant.q1_enc", "plant.q2_enc")),
                     ("simulate", 2.0, ("plant.q1_enc", "plant.q2_enc"))]
    assert capsys.readouterr().out.splitlines()[2] == \
        f"  {'drives in plant, RK4 x8':<32s} RMS 1.00e-06 m, max 2.00e-06 m, 3 encoder differences, 0.50 s"
    asked.clear()
    accurate_bench.main(["bench_triangle_TCx", "--stop-time", "0.5", "--substeps", "2"])
    assert asked[:2] == [("reference", "bench_triangle_TCx", 0.5), ("drives_in_plant", 2)]
