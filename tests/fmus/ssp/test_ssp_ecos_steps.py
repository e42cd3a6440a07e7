"""Ecos's stepping loop (fmus/ssp/run.py ``_ecos_steps``) with Ecos's simulation replaced by a
stand-in that keeps the time as Ecos does (no Ecos run needed): the rows after initialisation and
after every step; a component's String output ``refusal`` stopping the run with the master's
record, the instance named by the package's component; a foreign FMU (no such output) not
watched; and a step Ecos itself fails (an exception) recorded at the time of the step it failed,
with Ecos's message and its last error (issue 31: that branch ran in no test; a non-default step
size, so that a time computed from the step count and the wrong factor shows)."""
from __future__ import annotations

import numpy as np
import pytest

from fmus.ssp import run
from fmus.status import RunError, RunStatus

H = 2.5e-4


class Simulation:
    """Ecos's ``EcosSimulation`` as ``_ecos_steps`` calls it: ``x`` and ``y`` grow with the time;
    ``refuse_at`` (step index -> (component, record)) sets a component's ``refusal`` after that
    step; ``fail_at`` makes that step raise; ``foreign`` has no ``refusal``."""

    def __init__(self, refuse_at=None, fail_at=None):
        self.k, self.refuse_at, self.fail_at, self.refusals = 0, refuse_at or {}, fail_at, {}

    def get_time(self):
        return self.k * H

    def get_real(self, name):
        return {"plant::x": 1.0, "plant::y": -2.0}[name] * (1 + self.k)

    def get_string(self, name):
        component, variable = name.split("::")
        if component == "foreign" or variable != "refusal":
            raise RuntimeError(f"no {name}")
        return self.refusals.get(component, "")

    def step(self, n):
        assert n == 1
        if self.k == self.fail_at:
            raise RuntimeError("Ecos: step failed")
        if self.k in self.refuse_at:
            component, record = self.refuse_at[self.k]
            self.refusals[component] = record.to_json()
        self.k += 1


INSTANCES = {"plant": "resources/plant.fmu", "chain": "resources/chain.fmu", "foreign": "resources/f.fmu"}
IDS = ["plant::x", "plant::y"]


def _steps(sim, steps=4):
    data, times = np.full((steps + 1, 2), np.nan), []
    error = run._ecos_steps(sim, INSTANCES, IDS, data, times, steps, H)
    return error, data, times


def test_every_step_is_a_row_after_the_first_one():
    """Catches a row lost or shifted, the times not Ecos's, or a refusal made up."""
    error, data, times = _steps(Simulation())
    assert error is None and times == [k * H for k in range(5)]
    assert np.array_equal(data, [[1.0 + k, -2.0 * (1 + k)] for k in range(5)])


def test_a_step_ecos_fails_is_refused_at_its_start_with_ecos_words(monkeypatch):
    """Step 2 (from t = 2 h) raises: the record's time is 2 h, the message Ecos's and its last
    error, no instance; the rows before it kept.  Catches the time as the step count (or the
    step size) alone, and the last error left out."""
    monkeypatch.setattr("ecospy.EcosLib.get_last_error", staticmethod(lambda: "the last error"))
    error, data, times = _steps(Simulation(fail_at=2))
    assert (error.kind, error.instance, error.time) == (RunStatus.REFUSED, None, 2 * H)
    assert error.message == "Ecos: step failed the last error"
    assert times == [0.0, H, 2 * H] and np.isnan(data[3:]).all()


def test_a_components_refusal_stops_the_run_with_its_record_named_by_the_package():
    """The chain (a system FMU) refuses in the step from t = h, its record naming its inner plant
    after the path Ecos unpacked it to: the run's record is the chain's, instance "chain.plant",
    at t = h.  Catches the inner component lost or the unpacked path kept, the time of another step."""
    inner = RunError(RunStatus.REFUSED, "x0 out of reach", instance="/tmp/e/resources/chain.fmu.plant", time=H,
                     variable="x0", value=5.0)
    error, data, times = _steps(Simulation(refuse_at={1: ("chain", inner)}))
    assert (error.instance, error.time, error.variable, error.value) == ("chain.plant", H, "x0", 5.0)
    assert error.message == f"chain refused the step from t = {H:g} s: x0 out of reach"
    assert times == [0.0, H] and np.isnan(data[2:]).all()
