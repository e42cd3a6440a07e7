"""The native ClosedLoop (issue 28, item 1's goal): ``parcosim export-fmu SCENE OUT.fmu --native``.

Oracles: ``parcosim run`` of the scene (in process: the Python path of every component) for
the tracking error over the scene's window; the pythonfmu ClosedLoop (``export-fmu``) for
every output, the refusals and the FMU state's meaning; the FMU itself stepped again from a
restored state.  The build refuses by name a scene the compiled mode steps in Python."""
from __future__ import annotations

import re
import zipfile
from dataclasses import replace

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu

from tests.conftest import LOOP_SCENE
from fmus.native import state_bytes
from scenarios.metrics import scene_metrics
from scenarios.run import run_scene
from scenarios.scenes import get_scene
from tests.support.fmu_calls import Driver

pytestmark = [pytest.mark.fmu]

H = 1e-3


def _columns(result) -> dict:
    """The metrics' columns of an FMU's result (its outputs under their signal names)."""
    return {"t": result["time"], "x": result["x"], "y": result["y"], "x_d": result["traj.x_d"],
            "y_d": result["traj.y_d"], "tau1": result["ctrl.tau1"], "tau2": result["ctrl.tau2"]}


def test_native_loop_in_fmpy_tracks_as_parcosim_run(native_loop_fmu):
    """Catches a native ClosedLoop whose tracking in another importer (fmpy, 9 s) differs from parcosim
    run's beyond 1e-9 relative: a missing component, a wrong order or a stale parameter in the generated
    loop."""
    scene = get_scene(LOOP_SCENE)
    stop = scene.window[1] + 1.0                 # the window [1, 8] s and a second more: 9 s
    scene = replace(scene, system=replace(scene.system, stop_time=stop))
    expected = run_scene(scene, "inprocess", plots=False).metrics["e_ef_mm"]
    result = simulate_fmu(str(native_loop_fmu), stop_time=stop, step_size=H, output_interval=H)
    got = scene_metrics(scene, _columns(result), 0.0, True)["e_ef_mm"]
    assert got == pytest.approx(expected, rel=1e-9, abs=0.0)


def test_native_loop_declares_what_the_pythonfmu_closed_loop_declares(native_loop_fmu, twin_loop_fmu):
    """Catches a native loop FMU whose modelDescription (variables, references, starts, default experiment,
    identifier) drifts from the pythonfmu ClosedLoop it replaces, or that reuses the twin's GUID."""
    native, twin = read_model_description(str(native_loop_fmu)), read_model_description(str(twin_loop_fmu))

    def declared(md):
        return [(v.name, v.valueReference, v.type, v.causality, v.variability, v.start) for v in md.modelVariables]

    assert declared(native) == declared(twin) and len(declared(native)) > 100
    assert (native.modelName, native.coSimulation.modelIdentifier) == ("ClosedLoop", "ClosedLoop")
    for field in ("startTime", "stopTime", "stepSize"):
        assert getattr(native.defaultExperiment, field) == getattr(twin.defaultExperiment, field)
    assert native.coSimulation.canHandleVariableCommunicationStepSize
    assert native.guid != twin.guid and native.coSimulation.needsExecutionTool is False


def test_native_loop_equals_the_pythonfmu_closed_loop(native_loop_fmu, twin_loop_fmu):
    """Catches a native loop whose outputs differ from the pythonfmu twin's beyond 1e-12 of their peak over
    0.4 s, or one that does not move at all."""
    native = simulate_fmu(str(native_loop_fmu), stop_time=0.4, step_size=H, output_interval=H)
    twin = simulate_fmu(str(twin_loop_fmu), stop_time=0.4, step_size=H, output_interval=H)
    assert native.dtype.names == twin.dtype.names and len(native) == len(twin) == 401
    for name in twin.dtype.names:
        peak = np.max(np.abs(twin[name]))
        assert np.max(np.abs(native[name] - twin[name])) <= 1e-12 * peak, name
    assert np.ptp(native["x"]) > 1e-4          # the loop moved


def _outputs(driver):
    return np.array(driver.call("get", [v.name for v in driver.md.modelVariables if v.causality == "output"
                                        and v.type == "Real"]).result)


def _steps(driver, k0, k1, h=H):
    return [driver.call("step", k * h, h).status for k in range(k0, k1)]


def test_state_restored_serialised_and_in_a_fresh_instance_steps_on_as_the_twin(native_loop_fmu, twin_loop_fmu):
    """Catches an FMU state that misses part of the loop (a restored, deserialised or fresh-instance state
    stepping on differently from the uninterrupted run), and a fresh instance that cannot take a state
    before initialisation."""
    native, twin, fresh = Driver(native_loop_fmu), Driver(twin_loop_fmu), Driver(native_loop_fmu, "fresh")
    start = [("setup", 0.0), ("enter",), ("exit",)]
    for d in (native, twin):
        assert [s.status for s in d.run(start)] == [0, 0, 0]
        assert set(_steps(d, 0, 60)) == {0}
        d.call("getstate", "at60")
        assert set(_steps(d, 60, 120)) == {0}
    later = _outputs(native)
    np.testing.assert_allclose(later, _outputs(twin), rtol=0, atol=1e-12 * np.max(np.abs(later)))
    assert native.call("setstate", "at60").status == 0
    assert set(_steps(native, 60, 120)) == {0}
    assert np.array_equal(_outputs(native), later)
    native.call("serialize", "at60")
    data = native.states["at60"]
    fresh.call("bytes", "s", data)                # an instance never initialised: its loop is laid out on demand
    assert fresh.call("deserialize", "s").status == 0 and fresh.call("setstate", "s").status == 0
    assert set(_steps(fresh, 60, 120)) == {0}
    assert np.array_equal(_outputs(fresh), later)
    for d in (native, twin, fresh):
        d.close()


def _fixed_runs(fmu) -> list:
    """The (first word, words) runs the build found never changed (sources/loop_table.c)."""
    with zipfile.ZipFile(fmu) as z:
        text = z.read("sources/loop_table.c").decode()
    words = [int(w) for w in re.search(r"fixed\[\] = \{([^}]*)\}", text)[1].split(",")]
    return list(zip(words[::2], words[1::2]))


def test_forged_and_foreign_states_are_refused(native_loop_fmu, twin_loop_fmu):
    """Catches a deserialiser that accepts another FMU's state, a flipped byte, a truncated state or a
    changed build-fixed data word, or one that refuses the run state it must accept."""
    native, twin = Driver(native_loop_fmu), Driver(twin_loop_fmu)
    for d in (native, twin):
        d.run([("setup", 0.0), ("enter",), ("exit",), ("step", 0.0, H), ("getstate", "s"), ("serialize", "s")])
    own, foreign = native.states["s"], twin.states["s"]
    words = state_bytes.data_words(own)
    runs = _fixed_runs(native_loop_fmu)
    first, (last_start, last_count) = runs[0][0], runs[-1]
    mutable = next(k for k in range(len(words)) if not any(a <= k < a + n for a, n in runs))
    flipped = bytearray(own)
    flipped[len(own) // 3] ^= 0x10
    cases = [(foreign, "not a serialised parcosim native FMU state"), (bytes(flipped), "checksum"),
             (own[:-100], "long")]
    for index in (first, last_start + last_count - 1):
        cases.append((state_bytes.with_data_word(own, index, words[index] + 1.0),
                      f"word {index} of the loop's data differs from the build's"))
    for data, says in cases:
        native.call("bytes", "x", data)
        step = native.call("deserialize", "x")
        assert step.status == 3 and says in step.messages[0][2], (says, step.messages)
    native.call("bytes", "m", state_bytes.with_data_word(own, mutable, words[mutable] + 1e-3))
    assert native.call("deserialize", "m").status == 0      # run state may be anything the loop reaches
    twin.call("bytes", "n", own)
    assert twin.call("deserialize", "n").status == 3
    native.close()
    twin.close()


def test_step_sizes_and_communication_points_as_the_twin(native_loop_fmu, twin_loop_fmu):
    """Catches a native loop that accepts a step size or communication point its twin refuses (or the
    reverse), says it in other words, or steps a multiple of h differently from h steps one by one."""
    start = [("setup", 0.0), ("enter",), ("exit",), ("getstate", "0")]
    script = [("step", 0.0, 1.5e-3), ("setstate", "0"), ("step", 2e-3, H), ("setstate", "0"), ("step", 0.0, 5 * H),
              ("step", 5 * H, 2 * H)]
    native, twin = Driver(native_loop_fmu), Driver(twin_loop_fmu)
    calls = {}
    for name, d in (("native", native), ("twin", twin)):
        d.run(start)
        calls[name] = d.run(script)
    for n, t in zip(calls["native"], calls["twin"]):
        assert (n.call, n.status) == (t.call, t.status)
        assert [m[2] for m in n.messages] == [m[2] for m in t.messages], n.call
    assert [s.status for s in calls["native"]] == [2, 0, 2, 0, 0, 0]
    multiple = _outputs(native)
    one_by_one = Driver(native_loop_fmu)
    one_by_one.run(start[:3])
    assert set(_steps(one_by_one, 0, 7)) == {0}
    assert np.array_equal(_outputs(one_by_one), multiple)
    np.testing.assert_allclose(multiple, _outputs(twin), rtol=0, atol=1e-12 * np.max(np.abs(multiple)))
    for d in (native, twin, one_by_one):
        d.close()


def test_a_step_beyond_the_call_budget_is_refused_and_the_most_is_taken(native_loop_fmu, twin_loop_fmu):
    """Catches a call budget that is off by one step (the largest step it names refused, or one more
    accepted) or a huge step that is taken instead of refused."""
    native, twin = Driver(native_loop_fmu), Driver(twin_loop_fmu)
    for d in (native, twin):
        d.run([("setup", 0.0), ("enter",), ("exit",), ("getstate", "0")])
        assert d.call("step", 0.0, 1e3).status == 2      # a million steps in one call: both refuse
    message = native.call("setstate", "0") and native.call("step", 0.0, 1e3).messages[0][2]
    most = int(re.search(r"\((\d+) of its steps\)", message)[1])
    assert native.call("setstate", "0").status == 0
    assert native.call("step", 0.0, (most + 1) * H).status == 2
    assert native.call("setstate", "0").status == 0
    assert native.call("step", 0.0, most * H).status == 0
    native.close()
    twin.close()


def test_a_parameter_away_from_the_build_is_refused_by_name(native_loop_fmu):
    """Catches a native loop that silently runs with its built value when a parameter is set to another
    (the C has the build's values compiled in)."""
    native = Driver(native_loop_fmu)
    steps = native.run([("set", {"ctrl.lam": 30.0}), ("setup", 0.0), ("enter",), ("exit",), ("step", 0.0, H)])
    assert steps[-1].status == 2
    text = " ".join(m[2] for s in steps for m in s.messages)
    assert "parameter ctrl.lam = 30.0" in text and "built with ctrl.lam = " in text
    native.close()


def test_a_scene_the_compiled_mode_steps_in_python_is_refused_in_one_line(tmp_path, capsys):
    """Catches export-fmu --native writing a loop FMU for a scene whose controller table has holes (stepped
    in Python), or a refusal with a traceback or a file left behind."""
    from parcosim.cli import main

    out = tmp_path / "loop.fmu"
    assert main(["export-fmu", "bench_triangle_SMCx", str(out), "--native"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "component ctrl (PositionController)" in err[0] and "PC_LAW_TABLE_HOLE" in err[0]
    assert not out.exists()


def test_a_component_given_as_an_fmu_file_is_refused_by_name(tmp_path):
    """Catches a native loop export that drops or mis-builds a component given as a foreign FMU file
    instead of refusing it by name."""
    from fmus.native.loopbuild import NotNative, export_native_fmu

    system = get_scene(LOOP_SCENE).system
    components = tuple(replace(c, model=str(tmp_path / "deriv.fmu")) if c.name == "deriv" else c
                       for c in system.components)
    with pytest.raises(NotNative, match="component deriv is an FMU file"):
        export_native_fmu(replace(system, components=components), tmp_path / "loop.fmu")


def test_a_step_a_kernel_declines_after_the_export_run_is_refused_naming_it(tmp_path):
    """``bench_triangle_SMCx``'s controller meets a hole of its table at 0.755 s (the compiled
    mode takes that sample in Python): exported with a stop time before it, the FMU runs up
    to it and refuses that step (fmi2Discard) naming the component, its kernel and the code."""
    from fmus.native.loopbuild import export_native_fmu

    system = get_scene("bench_triangle_SMCx").system
    fmu = export_native_fmu(replace(system, stop_time=0.5), tmp_path / "loop.fmu")
    native = Driver(fmu)
    native.run([("setup", 0.0), ("enter",), ("exit",)])
    steps = [native.call("step", k * H, H) for k in range(800)]
    refused = [s.status for s in steps].index(2)
    assert {s.status for s in steps[:refused]} == {0} and 740 <= refused <= 760
    text = " ".join(m[2] for m in steps[refused].messages)
    assert "component ctrl (PositionController): its kernel pc_law_io declined the step from t = " in text
    assert "refusal code 8" in text
    native.close()


def _context_pointers(fmu) -> list:
    """The contexts a context points to in sources/loop_table.c's pcn_loop_fill (``&s->b<k>``)."""
    with zipfile.ZipFile(fmu) as z:
        text = z.read("sources/loop_table.c").decode()
    return re.findall(r"= (&s->b\d+)", re.search(r"pcn_loop_fill\(.*?\n\}", text, re.S)[0])


@pytest.mark.parametrize("scene, drives_in_plant, stop", [("pendulum_push", None, 1.5),
                                                          (LOOP_SCENE, 4, 0.3)])
def test_other_loops_equal_their_pythonfmu_closed_loops(scene, drives_in_plant, stop, tmp_path):
    """Other kernels, other contexts: the wheeled pendulum and its balance controller (the
    push at 1 s included), and the bench with its drives inside the plant (the actuated
    plant's context points to the plant's own: a context that points to another context)."""
    from fmus.systemfmu.export import export_fmu
    from fmus.native.loopbuild import export_native_fmu
    from scenarios.scenes import drives_in_plant as inside

    chosen = get_scene(scene) if drives_in_plant is None else inside(get_scene(scene), substeps=drives_in_plant)
    system = chosen.system
    native = export_native_fmu(system, tmp_path / "native" / "loop.fmu")
    twin = export_fmu(system, tmp_path / "twin" / "loop.fmu")
    if drives_in_plant is not None:
        assert _context_pointers(native)
    got = simulate_fmu(str(native), stop_time=stop, step_size=system.step, output_interval=system.step)
    expected = simulate_fmu(str(twin), stop_time=stop, step_size=system.step, output_interval=system.step)
    assert got.dtype.names == expected.dtype.names
    for name in expected.dtype.names:
        peak = np.max(np.abs(expected[name]))
        assert np.max(np.abs(got[name] - expected[name])) <= 1e-12 * peak, name
