"""The linear margin benchmark's building blocks (benchmarks/twin_linear_margin.py)."""
import numpy as np

from benchmarks.twin_linear_margin import delayed, lambda_limit, plant, setup
from controller.derivators import Derivator, _differentiator_ss


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
    derivator = _differentiator_ss(Derivator().velocity_sos, 1e-3)
    for G, _lam in families.values():
        limits = [lambda_limit(*delayed(*plant(Ml, Jr), d), G, derivator) for d in (1, 3, 6)]
        assert limits[0] > limits[1] > limits[2]
