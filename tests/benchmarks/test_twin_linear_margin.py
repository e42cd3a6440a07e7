"""The linear margin benchmark's building blocks (benchmarks/twin_linear_margin.py)."""
import numpy as np
import pytest

from benchmarks.twin_linear_margin import delayed, identify_edges, lambda_limit, plant, setup, start_limits, velocity_chain


def _impulse(Ad, Bd, Cm, steps=12):
    x, out = np.zeros(Ad.shape[0]), []
    for k in range(steps):
        x = Ad @ x + Bd @ (np.array([1.0, 0.0]) if k == 0 else np.zeros(2))
        out.append(Cm @ x)
    return np.array(out)


def test_delay_shifts_the_response_by_whole_samples():
    """A delay of d samples (d - 1 more than the loop's own) is the undelayed response d - 1
    samples later, nothing else: a shift register on the input, not a filter."""
    _point, Ml, Jr, _families = setup(0.0)
    system = plant(Ml, Jr)
    base = _impulse(*system)
    assert delayed(*system, 1) == system
    for d in (2, 4):
        late = _impulse(*delayed(*system, d))
        assert np.all(late[:d - 1] == 0.0)
        np.testing.assert_allclose(late[d - 1:], base[:len(base) - d + 1], rtol=1e-12, atol=0.0)


def test_more_delay_lowers_every_limit():
    """Each family's rigid λ limit at the start point falls as the delay grows (phase lag)."""
    _point, Ml, Jr, families = setup(0.0)
    derivator = velocity_chain()
    for G, _lam in families.values():
        limits = [lambda_limit(*delayed(*plant(Ml, Jr), d), G, derivator) for d in (1, 3, 6)]
        assert limits[0] > limits[1] > limits[2]


def test_effector_mass_lifts_pdx_and_the_filter_lowers_all():
    """The identification's two levers act as argued (docs/twin.md): an effector mass adds to
    the task-space inertia in every direction, so PDx's constant m* (set by the lightest task
    direction) gains margin against PDq's; a slower velocity filter lowers every limit."""
    light, heavy = start_limits(0.0, 0.0, 100.0), start_limits(0.0, 0.4, 100.0)
    assert heavy["PDx"] / heavy["PDq"] > light["PDx"] / light["PDq"] + 0.5
    slow = start_limits(0.0, 0.4, 11.0)
    assert all(slow[n] < heavy[n] for n in heavy)



def test_identification_ranks_by_the_misfit_to_the_bench_edges():
    """identify_edges returns its grid best first, each misfit the RMS log-ratio of that
    point's limits to the bench's edges (PDq 40, TC 65, PDx 75)."""
    rows = identify_edges(0.0, masses=[0.0, 0.4], cutoffs=[11.0, 100.0])
    assert [r[0] for r in rows] == sorted(r[0] for r in rows)
    best = rows[0]
    assert (best[1], best[2]) == (0.4, 11.0)
    expected = np.sqrt(np.mean(np.log([best[3]["PDq"] / 40, best[3]["TCq/TCx"] / 65, best[3]["PDx"] / 75]) ** 2))
    assert best[0] == pytest.approx(expected, rel=1e-12)
