"""The times a package's run reports (SspRun.wall_s, extra load_s, init_s, steps_s) are
durations of what they name: each >= 0, their parts within the run's wall time and that within
the call's own, and a loading made 0.2 s slower shows in the loading's time (issue 31: seed
3601's survivors [51] and [219], Ecos' ``load_s`` and fmpy's ``wall_s``, which no test read).
One Trajectory FMU, 5 steps in each tool."""
from __future__ import annotations

import time

import pytest

from fmus.cosim.system import Component, System
from fmus.export.build import build_fmu
from fmus.ssp.export import export_ssp
from fmus.ssp.run import simulate_ssp_ecos, simulate_ssp_fmpy
from tests.support.tools import UNAVAILABLE

pytestmark = [pytest.mark.fmu, pytest.mark.tools]

DELAY = 0.2     # s added to the loading


@pytest.fixture(scope="module")
def packages(tmp_path_factory):
    """(a package of one Trajectory, the same with kind = "nonsense", refused at initialisation)."""
    folder = tmp_path_factory.mktemp("timing")
    fmu = build_fmu("Trajectory", folder)

    def package(name, parameters):
        system = System((Component("traj", "Trajectory", parameters),), (), ("traj.x_d",), stop_time=0.005)
        return export_ssp(system, folder / f"{name}.ssp", fmus={"Trajectory": fmu})
    return package("good", {}), package("refused", {"kind": "nonsense"})


def _timed(run):
    start = time.perf_counter()
    result = run()
    return result, time.perf_counter() - start


def _slower(monkeypatch, module, name):
    """``module.name`` (a callable) made DELAY s slower."""
    real = getattr(module, name)

    def slow(*args, **kwargs):
        time.sleep(DELAY)
        return real(*args, **kwargs)
    monkeypatch.setattr(module, name, slow)


@pytest.mark.parametrize("which", [0, 1])
def test_fmpys_wall_time_is_the_runs_duration(packages, monkeypatch, which):
    """fmpy's runner made 0.2 s slower: wall_s is at least that and at most the call's own
    time, in a run that completes and in one refused at initialisation.  Catches the wall time
    as a sum of clock readings (seed 3601's [219]) or a reading alone."""
    import fmpy.ssp.simulation

    _slower(monkeypatch, fmpy.ssp.simulation, "simulate_ssp")
    run, elapsed = _timed(lambda: simulate_ssp_fmpy(packages[which]))
    assert (run.error is None) == (which == 0)
    assert DELAY <= run.wall_s <= elapsed


@pytest.mark.skipif(UNAVAILABLE["ecos"] is not None, reason=f"Ecos: {UNAVAILABLE['ecos']}")
@pytest.mark.parametrize("which", [0, 1])
def test_ecos_loading_time_is_the_loadings_duration_within_the_wall_time(packages, monkeypatch, which):
    """Ecos' loading made 0.2 s slower: 0.2 s <= load_s <= wall_s <= the call's own time.
    Catches ``load_s`` as a clock reading (seed 3601's [51]: ``loaded`` for ``loaded - start``)
    or a sum of two, and the wall time not the run's."""
    import ecospy

    _slower(monkeypatch, ecospy, "EcosSimulation")
    run, elapsed = _timed(lambda: simulate_ssp_ecos(packages[which], ["traj.x_d"]))
    assert (run.error is None) == (which == 0)
    assert DELAY <= run.extra["load_s"] <= run.wall_s <= elapsed
    assert run.wall_s - run.extra["load_s"] < elapsed - DELAY


@pytest.mark.skipif(UNAVAILABLE["libcosim"] is not None, reason=f"libcosim: {UNAVAILABLE['libcosim']}")
def test_libcosims_parts_add_up_within_its_wall_time(packages):
    """In libcosim's own process: loading, initialisation (the first step) and the other
    steps each take >= 0 s and together no more than the run's wall time, itself within the
    call's.  Catches any of them as a clock reading, a sum of two, or measured from another
    point."""
    from fmus.ssp.libcosim import simulate_ssp_libcosim

    run, elapsed = _timed(lambda: simulate_ssp_libcosim(packages[0], ["traj.x_d"], isolated=True))
    assert run.error is None and len(run.time) == 6
    parts = [run.extra[name] for name in ("load_s", "init_s", "steps_s")]
    assert min(parts) >= 0.0 and sum(parts) <= run.wall_s <= elapsed
