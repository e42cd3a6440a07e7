"""The exported packages in other people's tools, used plainly: fmpy's simulate_ssp, Ecos,
libcosim.  What is checked is what the user sees, the tracking: the RMS end-effector error
over [1, 2] s and the RMS torque of a 2 s copy of each scene, against ``parcosim run``.

The package (scenarios.package) models one thing differently from our master: the drives
integrated in the plant instead of separate (docs/actuated.md: 6.5e-6 m RMS apart over the
bench circle); the ratio is then 1 within 0.2 % on these scenes (docs/ssp.md).  The
bound asserted, 5 %, is the issue's goal; the per-component package, 90 times worse in
these tools, is far outside it.
"""
from __future__ import annotations

import dataclasses

import pytest

from fmus.ssp_run import ecos_available
from scenarios.scenes import get_scene
from scenarios.tools import compare, short

pytestmark = [pytest.mark.slow, pytest.mark.fmu, pytest.mark.tools]

SCENES = ("thesis_sim_circle", "bench_circle_TCMDx", "bench_circle_PDq", "bench_triangle_TCMDx")
STOP = 2.0


def _libcosim_reason():
    from fmus.libcosim_runner import libcosim_available

    return libcosim_available()


UNAVAILABLE = {"fmpy": None, "ecos": ecos_available(), "libcosim": _libcosim_reason()}
TOOLS = tuple(t for t, reason in UNAVAILABLE.items() if reason is None)


@pytest.fixture(scope="module", params=SCENES)
def compared(request, tmp_path_factory):
    scene = dataclasses.replace(short(get_scene(request.param), STOP), window=(1.0, STOP))
    return scene, compare(scene, TOOLS, isolated=False, out_dir=tmp_path_factory.mktemp("pkg"))


@pytest.mark.parametrize("tool", ("fmpy", "ecos", "libcosim"))
def test_the_package_tracks_in_the_tool_as_in_our_master(compared, tool):
    if UNAVAILABLE[tool] is not None:
        pytest.skip(f"{tool} cannot be loaded here: {UNAVAILABLE[tool]}")
    scene, rows = compared
    (_, m, ours, error), = [r for r in rows if r[0] == tool]
    assert m is not None and error is None and m["completed"], error
    assert 0.95 <= m["e_ef_mm"] / ours["e_ef_mm"] <= 1.05, (m["e_ef_mm"], ours["e_ef_mm"])
    assert 0.95 <= m["tau_ef_Nm"] / ours["tau_ef_Nm"] <= 1.05, (m["tau_ef_Nm"], ours["tau_ef_Nm"])
