"""``fmus.ssp.run.simulate_ssp_ecos`` with Ecos and the clock stood in (ecospy's objects replaced,
nothing is run): the run's ``wall_s`` and ``load_s`` are differences of the clock's readings,
and a package Ecos cannot initialise is a failed run naming Ecos' error."""
from __future__ import annotations

import zipfile

import pytest

ecospy = pytest.importorskip("ecospy")

from fmus.ssp import run as ssp_run  # noqa: E402
from fmus.ssp.export import NS  # noqa: E402
from fmus.status import RunError, RunStatus  # noqa: E402


class Clock:
    """time.perf_counter stood in: it starts at 100 s (so a reading added where it is subtracted
    shows) and moves 10 s while Ecos loads the package and 1 s a step."""

    def __init__(self):
        self.now = 100.0

    def perf_counter(self):
        return self.now


def package(path):
    """A package of one component (what simulate_ssp_ecos reads itself: its instances)."""
    ssd = (f'<ssd:SystemStructureDescription xmlns:ssd="{NS["ssd"]}" version="1.0" name="s">'
           '<ssd:System name="root"><ssd:Elements><ssd:Component name="plant" source="resources/plant.fmu"/>'
           '</ssd:Elements></ssd:System></ssd:SystemStructureDescription>')
    with zipfile.ZipFile(path, "w") as zf:
        zf.writestr("SystemStructure.ssd", ssd)
    return path


@pytest.fixture
def stand_ins(monkeypatch):
    """Ecos stood in: ``state["init"]`` says whether initialisation succeeds; the steps move the clock."""
    clock, state = Clock(), {"init": True, "freed": 0, "steps": 0}

    class Lib:
        set_log_level = staticmethod(lambda level: None)
        get_last_error = staticmethod(lambda: "the FMU said no")

    class Simulation:
        def __init__(self, step_size, ssp_path):
            clock.now += 10.0

        def init(self, t, parameter_set):
            return state["init"]

        def terminate(self):
            pass

        def free(self):
            state["freed"] += 1

    def steps(sim, instances, ids, data, times, count, step_size):
        assert instances == {"plant": "resources/plant.fmu"}
        for k in range(count + 1):
            times.append(k * step_size)
            if k:
                clock.now += 1.0
                state["steps"] += 1
        return None

    monkeypatch.setattr(ecospy, "EcosLib", Lib)
    monkeypatch.setattr(ecospy, "EcosSimulation", Simulation)
    monkeypatch.setattr(ssp_run, "_ecos_steps", steps)
    monkeypatch.setattr(ssp_run, "_time", clock)
    return state


def test_wall_s_and_load_s_are_the_runs_and_the_loadings_time(stand_ins, tmp_path):
    """4 steps: wall_s is the loading and the steps (14 s), load_s the loading (10 s), every
    row kept, and Ecos' simulation freed."""
    result = ssp_run.simulate_ssp_ecos(package(tmp_path / "p.ssp"), ["plant.x"], stop_time=4e-3, step_size=1e-3,
                                       serial=False)
    assert (result.wall_s, result.extra["load_s"]) == (14.0, 10.0)
    assert stand_ins["steps"] == 4 and len(result.time) == 5 and result.error is None and stand_ins["freed"] == 1


def test_a_package_ecos_cannot_initialise_is_a_failed_run_naming_ecos_error(stand_ins, tmp_path):
    """An initialisation refused: the run's error is an INITIALISATION record at t = 0 s naming
    Ecos' error and no instance, no step is taken and Ecos' simulation is freed."""
    stand_ins["init"] = False
    path = package(tmp_path / "p.ssp")
    result = ssp_run.simulate_ssp_ecos(path, ["plant.x"], stop_time=4e-3, step_size=1e-3, serial=False)
    assert result.error.kind is RunStatus.INITIALISATION and result.error.instance is None
    assert str(result.error) == f"Ecos could not initialise {path}: the FMU said no"
    # The whole record: the initialisation's time 0 s, and none of a model's fields (Ecos does
    # not say whose FMU failed nor why). Catches the time and the refusal's text swapped.
    assert result.error == RunError(RunStatus.INITIALISATION, f"Ecos could not initialise {path}: the FMU said no",
                                    time=0.0)
    assert result.error.record()["time"] == 0.0
    assert stand_ins["steps"] == 0 and stand_ins["freed"] == 1 and result.wall_s == 10.0


def test_the_signals_are_the_values_ecos_gives_in_the_order_asked(monkeypatch, tmp_path):
    """With the stepping loop itself (``_ecos_steps``) and the stand-in simulation of
    test_ssp_ecos_steps.py: each signal's column holds that variable's values after
    initialisation and after each step, in the order the signals were asked for, at Ecos' times."""
    from tests.fmus.ssp.test_ssp_ecos_steps import H, Simulation as Stepping

    class Lib:
        set_log_level = staticmethod(lambda level: None)
        get_last_error = staticmethod(lambda: "")

    class Simulation(Stepping):
        def __init__(self, step_size, ssp_path):
            super().__init__()

        def init(self, t, parameter_set):
            return True

        def terminate(self):
            pass

        def free(self):
            pass

    monkeypatch.setattr(ecospy, "EcosLib", Lib)
    monkeypatch.setattr(ecospy, "EcosSimulation", Simulation)
    result = ssp_run.simulate_ssp_ecos(package(tmp_path / "p.ssp"), ["plant.y", "plant.x"], stop_time=3 * H,
                                       step_size=H, serial=False)
    assert result.error is None and list(result.time) == [k * H for k in range(4)]
    assert list(result.signals) == ["plant.y", "plant.x"]
    assert list(result.signals["plant.y"]) == [-2.0 * (1 + k) for k in range(4)]
    assert list(result.signals["plant.x"]) == [1.0 * (1 + k) for k in range(4)]
