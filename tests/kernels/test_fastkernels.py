"""The per-step kernels (kernels/src/drive.c and observer.c, controller.fastderivator, controller.fasttrajectory):
a refused step changes nothing, so the Python path can take it again (fmus.cosim.compiled)."""
import math

import numpy as np
import pytest

import kernels
from controller.derivators import Derivator
from controller.trajectories import circle, triangle
from motor import CurrentObserver, Drive, get_motor_preset


def _twins(make):
    return make(), make()


def test_a_refused_drive_step_changes_nothing():
    """Catches a drive kernel that changes its state on a refused (NaN) step."""
    params = get_motor_preset("motor1")
    a, b = _twins(lambda: Drive(params, torque_output="mean", T=1e-3))
    inputs = [(0.3 * math.sin(k), 0.0, 2.0 * math.cos(k), 0.1 * k, 2.5e-4) for k in range(9)]
    for args in inputs[:5]:
        assert a.step(*args) == b.step(*args)
    with pytest.raises(ValueError, match="i_ref must be a finite number, got nan"):
        a.step(math.nan, *inputs[5][1:])
    with pytest.raises(ValueError, match="omega must be a finite number, got inf"):
        a.step(0.1, 0.0, math.inf, 0.0, 2.5e-4)
    for args in inputs[5:]:
        assert a.step(*args) == b.step(*args)      # bit for bit, phase and controller included


def test_a_refused_observer_step_changes_nothing():
    """Catches an observer kernel that changes its state on a refused (NaN) step."""
    a, b = _twins(lambda: CurrentObserver(get_motor_preset("motor2"), "dynamic"))
    for k in range(4):
        assert a.estimate(3.0 * k, 0.5 * k, 1e-3) == b.estimate(3.0 * k, 0.5 * k, 1e-3)
    with pytest.raises(ValueError, match="v must be a finite number, got nan"):
        a.estimate(math.nan, 1.0, 1e-3)
    for k in range(4, 8):
        assert a.estimate(3.0 * k, 0.5 * k, 1e-3) == b.estimate(3.0 * k, 0.5 * k, 1e-3)


def test_a_refused_derivator_sample_changes_nothing():
    """Catches a derivator kernel that changes its filters on a refused (NaN) sample."""
    a, b = _twins(Derivator)
    a.reset([0.1, -0.2])
    b.reset([0.1, -0.2])
    q = [(0.1 + 1e-3 * k, -0.2 + 2e-3 * k * k) for k in range(40)]
    for sample in q[:20]:
        assert all(np.array_equal(x, y) for x, y in zip(a.step(sample), b.step(sample)))
    with pytest.raises(ValueError, match=r"angles q = \[0.1, nan\] rad must be finite"):
        a.step([0.1, math.nan])
    for sample in q[20:]:
        assert all(np.array_equal(x, y) for x, y in zip(a.step(sample), b.step(sample)))


@pytest.mark.parametrize("trajectory", [circle(), triangle()], ids=["circle", "triangle"])
def test_trajectory_refuses_negative_time_and_is_continuous_at_its_end(trajectory):
    """Catches a trajectory kernel that accepts t < 0 or jumps at its end."""
    with pytest.raises(ValueError, match="trajectory time must be >= 0 s, got -0.001"):
        trajectory(-0.001)
    before, after = trajectory(trajectory.duration - 1e-9), trajectory(trajectory.duration)
    assert math.hypot(before.x - after.x, before.y - after.y) < 1e-6


@pytest.mark.parametrize("yaw", [True, False])
def test_balance_kernel_is_the_observer_and_lqr_written_with_numpy(yaw):
    # The BalanceController object against the numpy oracle (tests/kernels/test_kernels_wheeled.py),
    # on the real design.
    """Catches a balance kernel whose observer or LQR differs from the numpy oracle."""
    from controller import fastbalance
    from controller.balance import BalanceController, BalanceSettings, design_balance, get_route
    from tests.kernels.test_kernels_wheeled import numpy_balance

    design = design_balance(BalanceSettings(yaw=yaw, v_battery=2.0))
    controller = BalanceController(design, get_route("forward_turn"))
    for t, sensors, u, x_hat, x_d in numpy_balance(design, controller.route, yaw, 400):
        assert controller.sample(t, *sensors) == pytest.approx(tuple(u), rel=1e-12, abs=1e-12)
        np.testing.assert_allclose(controller.x_hat, x_hat, rtol=1e-12, atol=1e-12)
        assert controller.io[fastbalance.O_REF] == pytest.approx(x_d, rel=1e-12, abs=1e-15)
    saved = controller.buf.copy()
    io = np.array([0.1, float("nan"), 0.0] + [0.0] * len(fastbalance.OUTPUTS))
    assert fastbalance.sample(controller.buf, io, 8.0, 1e6, kernels.Refusal()) == fastbalance.BAD_INPUT
    assert np.array_equal(controller.buf, saved)
