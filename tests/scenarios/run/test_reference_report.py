"""What the monolithic reference reports besides its rows (scenarios/reference.py): the progress
it calls back, its mean solver steps per interval, and the lines of ``python -m
scenarios.reference --variants`` (the decomposition of the master's deviation)."""
from __future__ import annotations

import re

import pytest

from scenarios import reference


def test_progress_rises_to_one_once_per_percent_and_the_mean_steps_count_every_interval():
    """0.25 s at 1 ms is 250 intervals: progress is called every 2 intervals (250 // 100) with the
    fraction done, k / 250 for k = 2, 4, ..., 250, ending at exactly 1; the mean solver steps per
    interval is the plant's steps over the 250 intervals.  Catches a fraction of the step before
    (never reaching 1), a product instead of a ratio, or a count off by one."""
    seen = []
    result = reference.reference_run("thesis_sim_circle", stop_time=0.25, progress=seen.append)
    assert result.completed and len(result.time) == 251
    assert seen == [pytest.approx(k / 250, abs=1e-15) for k in range(2, 251, 2)] and seen[-1] == 1.0
    assert result.extra["mean_steps_per_interval"] == pytest.approx(result.steps / 250, rel=1e-15)
    assert result.steps >= 250


def _rms(out: str, label: str) -> float:
    line = next(line for line in out.splitlines() if line.startswith(label))
    return float(re.search(r"all: rms ([0-9.e+-]+)", line).group(1))


def test_the_variants_decompose_the_deviation_of_a_lugre_scene(capsys):
    """``--variants`` on the twin's LuGre scene, 0.02 s: every variant runs (mu = 0 turns the LuGre
    drives to tanh friction, which LuGre without mu refuses); the reference with the master's
    coupling deviates from the reference as the master does (they agree to 1e-12 m here, the
    deviations are 1e-6 m); the master deviates from that reference by < 1e-9 m; every other line
    compares two different runs.  Catches a line comparing a run with itself (0), a line left
    out, and a variant the LuGre drives refuse."""
    assert reference.main(["bench_real_circle_TCMDx", "--stop-time", "0.02", "--variants"]) == 0
    out = capsys.readouterr().out
    assert "STOPPED" not in out
    assert out.startswith("bench_real_circle_TCMDx, 0-0.02 s: reference DOP853 rtol 1e-10 atol 1e-13, ")  # defaults
    master = _rms(out, "master - reference")
    assert master > 1e-7
    assert _rms(out, "reference(cosim coupling) - reference") == pytest.approx(master, rel=0.02)
    assert _rms(out, "  master - reference(cosim): plant RK4") < 1e-9
    assert _rms(out, "mu = 0: master - reference") > 0.0
    labels = ("mu = 0 and encoder 2^30: master - reference", "encoder 2^30 counts: master - reference",
              "reference(mean torque) - reference", "  ref(held_speed) - reference: speed held")
    assert all(_rms(out, label) > 0.0 for label in labels)
    compared = [line.split(" | ")[0].rstrip() for line in out.splitlines() if "all: rms" in line]
    assert compared == ["master - reference", "reference(cosim coupling) - reference",
                        "  master - reference(cosim): plant RK4", "  ref(cosim) - ref(held_speed): torque held",
                        "  ref(held_speed) - reference: speed held", "reference(mean torque) - reference",
                        "master, plant RK4 substeps=4 - reference", "master, plant Component substeps=4 - ref.",
                        "encoder 2^30 counts: master - reference", "mu = 0: master - reference",
                        "mu = 0 and encoder 2^30: master - reference"]
    assert all(_rms(out, label) > 0.0 for label in compared if label != "  master - reference(cosim): plant RK4")


def test_the_reference_refuses_what_it_cannot_integrate_naming_what_and_why():
    """Each refusal names the culprit: a non-scene (its type), no FiveBarPlant (and, for the scene
    with its drives in the plant, why), an unknown coupling (the valid ones), an unknown
    parameter (component, model, name), a drive whose period differs from the step (both values),
    a drive the initialisation refuses (its message and time), a voltage-mode drive without
    inductance given through ``system_changes``, an unknown model, a drive fed another joint's
    speed.  Catches a refusal that names another component or value, a check skipped, the
    system changes not applied."""
    from scenarios.scenes.catalogue import get_scene
    from scenarios.scenes.transforms import drives_in_plant

    scene = get_scene("bench_circle_PDq")

    def refusal(kind, *args, **kwargs):
        with pytest.raises(kind) as caught:
            reference.reference_run(*args, stop_time=0.01, **kwargs)
        return str(caught.value)

    assert refusal(TypeError, 42) == "expected a scene name, a Scene or a System, got int"
    assert refusal(reference.ReferenceError, "pendulum_balance") == \
        "the reference needs exactly one FiveBarPlant, found 0"
    assert refusal(reference.ReferenceError, drives_in_plant(scene)) == (
        "the reference needs exactly one FiveBarPlant, found 0 (plant is an ActuatedFiveBarPlant: its truth is "
        "the reference of the scene before scenarios.scenes.transforms.drives_in_plant)")
    assert refusal(ValueError, scene, coupling="jacobi") == \
        f"coupling = 'jacobi'; valid: {', '.join(reference.COUPLINGS)}"
    assert refusal(reference.ReferenceError, reference.with_parameters(scene.system, "plant", bogus=1.0)) == \
        "component plant: FiveBarPlant has no parameter 'bogus'"
    assert refusal(reference.ReferenceError, reference.with_parameters(scene.system, "drive2", T=2e-3)) == \
        "drive drive2: controller period T = 0.002 s differs from the step 0.001 s"
    message = refusal(reference.ReferenceError, reference.with_parameters(scene.system, "drive2", L=0.0))
    assert message.startswith("drive2: initialisation refused: ") and "needs L > 0, got L=0.0 (t = 0 s)" in message
    assert refusal(reference.ReferenceError, scene, system_changes=lambda s: reference.with_parameters(
        s, "drive2", L=0.0, mode="voltage")) == "drive drive2: L = 0 has no electrical state to integrate"
    from dataclasses import replace

    from fmus.cosim.system import Connection

    unknown = replace(scene.system, components=tuple(replace(c, model="NoSuchModel") if c.name == "obs1" else c
                                                     for c in scene.system.components))
    assert refusal(reference.ReferenceError, unknown).startswith("component obs1: unknown model 'NoSuchModel'; valid: ")
    crossed = replace(scene.system, connections=tuple(Connection("plant.dq2", c.target) if c.target == "drive1.omega"
                                                      else c for c in scene.system.connections))
    assert refusal(reference.ReferenceError, crossed) == "drive drive1: omega must be plant.dq1 (got plant.dq2)"


def test_the_report_at_given_tolerances_prints_each_comparison_over_each_window(capsys):
    """``python -m scenarios.reference SCENE --stop-time 0.12 --rtol 1e-8 --atol 1e-11
    --convergence``: the header names the scene, the stop, the method and the tolerances given;
    the convergence lines compare runs at rtol, atol / 2 and / 10 with the reference, and the
    master's line the master, each over the whole run and the windows [0, 0.1] and [0.1, 0.12],
    every figure that of ``deviation`` of runs made here with those tolerances; without
    --variants nothing more.  Catches the tolerances not reaching the runs, a factor applied to
    one of them only, a window's edge moved, a line comparing other runs."""
    from dataclasses import replace

    from fmus.cosim.master import simulate
    from scenarios.scenes.catalogue import get_scene

    assert reference.main(["bench_circle_TCMDx", "--stop-time", "0.12", "--rtol", "1e-8", "--atol", "1e-11",
                           "--convergence"]) == 0
    lines = capsys.readouterr().out.splitlines()
    system = replace(get_scene("bench_circle_TCMDx").system, stop_time=0.12)
    ref = reference.reference_run(system, rtol=1e-8, atol=1e-11)
    assert lines[0].startswith("bench_circle_TCMDx, 0-0.12 s: reference DOP853 rtol 1e-08 atol 1e-11, ")
    assert lines[0].endswith(f"{ref.nfev} evaluations, {ref.extra['mean_steps_per_interval']:.2f} steps per interval")

    def line(label, result):
        parts = [f"{label:<44s}"]
        d = reference.deviation(result, ref)
        parts.append(f"all: rms {d['rms']:.2e} max {d['max']:.2e} (t {d['t_max']:.3f})")
        for a, b in ((0.0, 0.1), (0.1, 0.12)):
            d = reference.deviation(result, ref, a, b)
            parts.append(f"[{a:g},{b:g}]: rms {d['rms']:.2e} max {d['max']:.2e}")
        return " | ".join(parts)

    half = reference.reference_run(system, rtol=5e-9, atol=5e-12)
    tenth = reference.reference_run(system, rtol=1e-9, atol=1e-12)
    assert lines[1] == line("reference at rtol, atol / 2", half)
    assert lines[2] == line("reference at rtol, atol / 10", tenth)
    assert lines[3].startswith("master (in-process, defaults): ") and "STOPPED" not in lines[3]
    assert lines[4] == line("master - reference", simulate(system)) and len(lines) == 5
    assert reference.deviation(half, ref)["max"] > 0.0


def test_the_windows_split_at_a_tenth_of_a_second_and_where_the_reference_stops():
    """Catches the first window's end not clipped to a short run, the reference's end added
    when it lies beyond the run (or for a bare System, which has none), an empty window."""
    from dataclasses import replace

    from scenarios.scenes.catalogue import get_scene

    scene = get_scene("bench_circle_TCMDx")
    assert reference._windows(0.05, scene) == [(0.0, 0.05)]
    assert reference._windows(0.1, scene) == [(0.0, 0.1)]
    assert reference._windows(0.3, scene) == [(0.0, 0.1), (0.1, 0.3)]
    ends = replace(scene, reference_end=0.2)
    assert reference._windows(0.3, ends) == [(0.0, 0.1), (0.1, 0.2), (0.2, 0.3)]
    assert reference._windows(0.2, ends) == [(0.0, 0.1), (0.1, 0.2)]
    assert reference._windows(0.3, ends.system) == [(0.0, 0.1), (0.1, 0.3)]


def _recorded_report(monkeypatch, capsys, argv):
    """``reference.main(argv)`` with the runs replaced by records of what they were asked (the
    system, the keyword arguments): {label: (result compared, reference compared)} per printed
    line, and every reference run.  ``deviation`` answers the number of its call as the rms, which
    tells which two runs each line compared."""
    import types

    import fmus.cosim.master

    runs, compared = [], []

    def reference_run(system, **kwargs):
        plant = next(c.name for c in system.components if c.model == "FiveBarPlant")
        run = types.SimpleNamespace(system=system, kwargs=kwargs, method="DOP853", rtol=kwargs["rtol"],
                                    atol=kwargs["atol"], wall_s=0.0, nfev=0, completed=True, error="",
                                    extra={"mean_steps_per_interval": 1.0, "plant": plant})
        runs.append(run)
        return run

    def simulate(system):
        return types.SimpleNamespace(system=system, kwargs=None, wall_s=0.0, completed=True, error=None)

    def deviation(result, ref, a=None, b=None):
        compared.append((result, ref))
        return {"rms": float(len(compared) - 1), "max": 0.0, "t_max": 0.0}

    monkeypatch.setattr(reference, "reference_run", reference_run)
    monkeypatch.setattr(reference, "deviation", deviation)
    monkeypatch.setattr(fmus.cosim.master, "simulate", simulate)
    assert reference.main(argv) == 0
    lines = [line for line in capsys.readouterr().out.splitlines() if "all: rms" in line]
    return {line.split(" | ")[0].rstrip(): compared[int(_rms(line, ""))] for line in lines}, runs


def _params(run, name):
    return run.system.component(name).parameters


def test_each_variant_line_compares_the_runs_its_label_names(monkeypatch, capsys):
    """``--variants`` on the twin's LuGre scene (drives, encoders): each line's two runs are those
    its label names, read back from the systems and arguments they got: the three couplings, the
    plant's RK4 substeps = 4 as a parameter and as the master's Component substeps, the encoder
    at exactly 2^30 counts on both sides, mu = 0 on every drive (LuGre ones turned to tanh, which
    needs no mu), both at once; every reference at the tolerances given.  Seed 4101 [101] (the
    encoder's counts 2 * 30 went unseen: its line still differs from 0) and its siblings: a
    coupling, a substep count, a drive or a variant's side left unchanged."""
    from dataclasses import replace

    from scenarios.scenes.catalogue import get_scene

    scene = get_scene("bench_real_circle_TCMDx")
    lines, runs = _recorded_report(monkeypatch, capsys, [scene.name, "--stop-time", "0.02", "--rtol", "3e-9",
                                                         "--variants"])
    base = scene.system
    assert all(r.kwargs["rtol"] == 3e-9 and r.kwargs["atol"] == reference.ATOL for r in runs)
    assert all(r.system.stop_time == 0.02 for r in runs)
    master, ref = lines["master - reference"]
    assert master.kwargs is None and ref.kwargs == {"rtol": 3e-9, "atol": reference.ATOL}
    assert master.system == ref.system == replace(base, stop_time=0.02)
    couplings = {label: tuple(r.kwargs and r.kwargs.get("coupling") for r in pair) for label, pair in lines.items()}
    assert couplings["reference(cosim coupling) - reference"] == ("cosim", None)
    assert couplings["  master - reference(cosim): plant RK4"] == (None, "cosim")
    assert couplings["  ref(cosim) - ref(held_speed): torque held"] == ("cosim", "held_speed")
    assert couplings["  ref(held_speed) - reference: speed held"] == ("held_speed", None)
    assert couplings["reference(mean torque) - reference"] == ("mean", None)

    rk4, ref = lines["master, plant RK4 substeps=4 - reference"]
    assert _params(rk4, "plant") == {**_params(ref, "plant"), "substeps": 4}
    assert rk4.system.component("plant").substeps == ref.system.component("plant").substeps == 1
    multi, ref = lines["master, plant Component substeps=4 - ref."]
    assert multi.system.component("plant").substeps == 4 and _params(multi, "plant") == _params(ref, "plant")

    drives = ("drive1", "drive2")
    for label, encoder, friction in (("encoder 2^30 counts", True, False), ("mu = 0", False, True),
                                     ("mu = 0 and encoder 2^30", True, True)):
        pair = lines[f"{label}: master - reference"]
        assert pair[0].kwargs is None and pair[1].kwargs == {"rtol": 3e-9, "atol": reference.ATOL}
        assert pair[0].system == pair[1].system, label   # the same change on both sides
        plant = _params(pair[0], "plant")
        assert plant.get("encoder_counts") == (2 ** 30 if encoder else None), label
        for d in drives:
            expected = {**base.component(d).parameters, "mu": 0.0, "friction": "tanh"} if friction \
                else base.component(d).parameters
            assert _params(pair[0], d) == expected, (label, d)
        others = [c for c in pair[0].system.components if c.name not in drives + ("plant",)]
        assert others == [c for c in base.components if c.name not in drives + ("plant",)]


def test_a_scene_without_drives_or_encoders_has_no_coupling_or_variant_lines(monkeypatch, capsys):
    """The thesis' ideal-actuator scene: no drives (no coupling lines, no mu = 0), no encoder (no
    2^30 line): only the master against the reference and the two substep lines remain, at the
    default tolerances.  Catches a variant offered where it changes nothing."""
    lines, runs = _recorded_report(monkeypatch, capsys, ["thesis_sim_circle", "--stop-time", "0.02", "--variants"])
    assert list(lines) == ["master - reference", "master, plant RK4 substeps=4 - reference",
                           "master, plant Component substeps=4 - ref."]
    assert [r.kwargs for r in runs] == [{"rtol": reference.RTOL, "atol": reference.ATOL}]
