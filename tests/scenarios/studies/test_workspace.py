"""The workspace figure (scenarios/studies/workspace/): loci, refusals, the CLI."""
import json
import subprocess
import sys

import numpy as np
import pytest

from plant import fivebar, get_preset
from plant import spec as plant_spec
from plant.specsim import assemble
from scenarios.studies import workspace
from scenarios.studies.workspace.spec import measures


def parallel_singular_point(params, x=0.0, lo=0.03, hi=0.1):
    """A point of the det J_X = 0 locus on the line x = 0, by bisection of seed 002's det J_X (eq. 16)."""
    def det_x(y):
        ang = fivebar.inverse_kinematics(params, x, y)
        return np.linalg.det(fivebar.jacobians(params, x, y, ang[0], ang[2])[0])
    assert det_x(lo) * det_x(hi) < 0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if det_x(lo) * det_x(mid) > 0 else (lo, mid)
    return x, 0.5 * (lo + hi)


def test_signed_measures_are_the_jacobians_determinants():
    """Catches the workspace map's singularity measures normalised otherwise, or of other Jacobians, than
    det J_X / l2^2 and det J_theta / (l1 l2)^2 at each point."""
    params = get_preset("bench")
    ws = fivebar.workspace_map(params, step=0.02, extent=(-0.1, 0.1, 0.05, 0.25))
    det_x, det_t = workspace.signed_measures(params, ws)
    for iy, ix in zip(*np.nonzero(~np.isnan(ws.margin))):
        x, y = ws.x[ix], ws.y[iy]
        ang = fivebar.inverse_kinematics(params, x, y)
        JX, JT = fivebar.jacobians(params, x, y, ang[0], ang[2])
        l1, l2 = params.chain1.l1, params.chain1.l2
        assert det_x[iy, ix] == pytest.approx(np.linalg.det(JX) / l2 ** 2, abs=1e-12)
        assert det_t[iy, ix] == pytest.approx(np.linalg.det(JT) / (l1 * l2) ** 2, abs=1e-12)


def test_the_thesis_trajectories_are_accepted_and_bad_circles_refused_with_their_reason():
    """Catches a trajectory check that refuses the thesis paths, accepts a circle leaving the workspace or
    crossing the parallel singularity, or gives no time of the first refusal."""
    params = get_preset("bench")
    for name, ref in workspace.thesis_trajectories("bench").items():
        check = workspace.check_trajectory(params, name, ref, ref.duration)
        assert not any(len(i) for i in check.refused.values()) and check.min_margin > 0.3
    too_high = workspace.check_trajectory(params, "high", workspace.user_circle(0.0, 0.2, 0.09), 1.0)
    assert len(too_high.refused[workspace.OUTSIDE]) > 100
    x, y = parallel_singular_point(params)
    through = workspace.check_trajectory(params, "low", workspace.user_circle(x, y + 0.05, 0.05), 1.0)
    assert len(through.refused[workspace.BAND]) > 0 and through.min_margin < 1e-2
    assert through.summary()["first_refusal_s"] is not None


def test_first_refusal_time_is_the_sample_index_times_the_sample_time():
    """The same circle through the near-singular band, sampled at 1 ms and at 2 ms: the first
    refused sample is at the same time (within one sample) and its index times the sample time
    (wrong code it catches: an index read as milliseconds whatever the sample time)."""
    params = get_preset("bench")
    x, y = parallel_singular_point(params)
    circle = workspace.user_circle(x, y + 0.05, 0.05)

    def ref(t):   # started half a turn later: it enters the band near t = 0.39 s, not at once
        return circle(t + 0.5)

    fine = workspace.check_trajectory(params, "low", ref, 1.0)
    coarse = workspace.check_trajectory(params, "low", ref, 1.0, sample_time=2e-3)
    first = min(int(i[0]) for i in coarse.refused.values() if len(i))
    assert coarse.summary()["first_refusal_s"] == pytest.approx(first * 2e-3)
    assert abs(coarse.summary()["first_refusal_s"] - fine.summary()["first_refusal_s"]) <= 2e-3
    assert 0.3 < fine.summary()["first_refusal_s"] < 0.5


def test_spec_measures_vanish_on_the_parallel_locus():
    """Catches the spec mechanism's singularity measures not vanishing on the 5R's parallel singular locus
    (another measure, or the wrong closure)."""
    spec = plant_spec.load("bench_5r")
    x, y = parallel_singular_point(get_preset("bench"))
    near = assemble(spec, (x, y + 1e-7, 0.0))
    assert measures(spec.mechanism, near)[1] < 1e-5
    assert min(measures(spec.mechanism, assemble(spec, spec.start))) > 0.1


def test_cli_writes_the_figure_and_the_verdicts(tmp_path):
    """Catches parcosim workspace writing no figure or JSON, dropping the thesis paths, or accepting a
    malformed --circle."""
    out = subprocess.run([sys.executable, "-m", "parcosim", "workspace", "bench", "--out", str(tmp_path),
                          "--circle", "0,0.2,0.09"], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert "REFUSED" in out.stdout and "triangle (7.24-7.27)" in out.stdout
    assert (tmp_path / "workspace.png").stat().st_size > 10000
    data = json.loads((tmp_path / "workspace.json").read_text())
    assert [t["name"] for t in data["trajectories"]][:2] == ["circle (7.23)", "triangle (7.24-7.27)"]
    bad = subprocess.run([sys.executable, "-m", "parcosim", "workspace", "bench", "--circle", "0,0.2"],
                         capture_output=True, text=True, timeout=300)
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "--circle" in bad.stderr
