"""The controller's range checks hit exactly at their bounds, on both sides (session 44, training
sample 4421's lesson: a refusal ``x <= 0`` and ``x < 0`` differ only at x = 0 itself).

Each bound is the documented one (the settings' docstrings, the refusal texts): the bound itself
is accepted where the range is closed and refused, by name and value, where it is open, and the
next floating-point number on the other side does the opposite."""
from __future__ import annotations

import math
import re
import warnings

import numpy as np
import pytest

import kernels
from controller import fastbalance, law
from controller.balance import MIN_SAMPLE_TIME, BalanceController, BalanceSettings, design_balance
from controller.derivators import bessel_lowpass_sos
from controller.fasttrajectory import MAX_CYCLES
from controller.model import TabulatedModel, perturbed_params
from controller.position import PositionController
from controller.strategies import get_strategy
from controller.trajectories import from_parameters, get_trajectory
from plant import get_preset

BENCH = get_preset("bench")


def refused(text):
    """pytest.raises for a ValueError whose message is ``text`` word for word."""
    return pytest.raises(ValueError, match="^" + re.escape(text) + "$")


def test_the_balance_sample_time_is_accepted_at_both_ends_of_its_closed_range():
    """T in [MIN_SAMPLE_TIME, 1] s: both ends taken, the next number outside each refused."""
    assert MIN_SAMPLE_TIME == 1e-5
    for T in (MIN_SAMPLE_TIME, 1.0):
        assert BalanceSettings(T=T).validate().T == T
    for T in (math.nextafter(MIN_SAMPLE_TIME, 0.0), math.nextafter(1.0, 2.0)):
        with refused(f"parameter T = {T!r} s must be in [1e-05, 1] s"):
            BalanceSettings(T=T).validate()


def test_a_balance_battery_of_zero_volts_and_zero_encoder_counts_are_refused_the_smallest_above_taken():
    """v_battery > 0 and encoder_counts > 0 (a positive integer): 0 itself refused by name."""
    with refused("parameter v_battery = 0.0 V must be > 0"):
        BalanceSettings(v_battery=0.0).validate()
    assert BalanceSettings(v_battery=math.ulp(0.0)).validate().v_battery == math.ulp(0.0)
    with refused("parameter encoder_counts = 0 must be a positive integer"):
        BalanceSettings(encoder_counts=0).validate()
    assert BalanceSettings(encoder_counts=1).validate().encoder_counts == 1


def test_a_bessel_cut_off_of_zero_is_refused_like_one_at_nyquist():
    """0 < fc < 1/(2T) is an open interval: fc = 0 (no pass band) is refused with the same
    sentence as fc at Nyquist, before scipy is asked."""
    T = 1e-3
    with refused(f"cut-off 0.0 Hz must lie in (0, {0.5 / T}) Hz for T = {T} s"):
        bessel_lowpass_sos(2, 0.0, T)
    sos = bessel_lowpass_sos(2, 1.0, T)
    assert sos.shape == (1, 6)


@pytest.fixture(scope="module")
def balance():
    return BalanceController(design_balance(BalanceSettings(yaw=False)))


def test_balance_kernel_arrays_of_exactly_their_size_are_taken_and_one_word_short_refused(balance):
    """fastbalance.sample needs float64 arrays of >= BUF_SIZE and >= IO_SIZE words: arrays of
    exactly that size are sampled (a code, not a ValueError); one word fewer is refused."""
    buf = np.array(balance.buf[:fastbalance.BUF_SIZE], dtype=np.float64)
    x = np.zeros(fastbalance.IO_SIZE)
    assert buf.size == fastbalance.BUF_SIZE
    assert fastbalance.sample(buf, x, 0.0, math.inf, kernels.Refusal()) == fastbalance.OK
    with refused(f"a balance kernel buffer must be a float64 array of >= {fastbalance.BUF_SIZE} words"):
        fastbalance.sample(buf[:-1].copy(), x, 0.0, math.inf, kernels.Refusal())
    with refused(f"a balance kernel buffer must be a float64 array of >= {fastbalance.IO_SIZE} words"):
        fastbalance.sample(buf, x[:-1].copy(), 0.0, math.inf, kernels.Refusal())


def test_every_balance_buffer_word_has_exactly_one_name_its_fields_own():
    """WORD_NAMES: one name a word (BUF_SIZE of them), a one-word field by its name and the k-th
    word of a longer field as name[k], from each field's first word to its last."""
    assert len(fastbalance.WORD_NAMES) == fastbalance.BUF_SIZE
    for name, s in fastbalance.BUFFER.items():
        words = fastbalance.WORD_NAMES[s.start:s.stop]
        if s.stop - s.start == 1:
            assert words == (name,)
        else:
            assert words == tuple(f"{name}[{k}]" for k in range(s.stop - s.start))


def test_a_model_error_of_exactly_minus_one_is_refused_and_the_next_number_above_scales():
    """model_error > -1 (a factor 1 + e > 0 on every mass and inertia): -1 itself, the massless
    model, is refused; the next number above it scales the masses by 1 + e > 0."""
    with refused("model_error = -1.0 must be finite and > -1"):
        perturbed_params(BENCH, -1.0)
    e = math.nextafter(-1.0, 0.0)
    scaled = perturbed_params(BENCH, e)
    assert scaled.chain1.m1 == BENCH.chain1.m1 * (1.0 + e) > 0.0
    assert scaled.m0 == BENCH.m0 * (1.0 + e)


def test_a_cached_table_of_two_lines_a_side_is_loaded_again_without_a_rebuild(tmp_path, monkeypatch):
    """The smallest table accepted (2 x 2 points) is also the smallest one read back from the
    cache: the second model loads it (no warning, no build time) with the same values."""
    monkeypatch.setenv("PARCOSIM_CACHE", str(tmp_path))
    extent = (-0.05, 0.05, 0.1, 0.2)
    first = TabulatedModel(BENCH, 0.1, extent)
    assert len(list(tmp_path.iterdir())) == 1
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        again = TabulatedModel(BENCH, 0.1, extent)
    assert (again.xs.size, again.ys.size) == (2, 2) and again.build_seconds == 0.0
    assert np.array_equal(again.table, first.table)


def test_a_grid_step_of_zero_and_an_extent_of_zero_width_or_height_are_refused():
    """step > 0 and x_max > x_min, y_max > y_min: equality is refused by name."""
    with refused("grid step = 0.0 m must be > 0"):
        TabulatedModel(BENCH, 0.0, (-0.05, 0.05, 0.1, 0.2), cache=False)
    for extent in ((0.05, 0.05, 0.1, 0.2), (-0.05, 0.05, 0.2, 0.2)):
        with refused(f"extent = {extent!r} is empty"):
            TabulatedModel(BENCH, 0.1, extent, cache=False)


def test_a_position_controller_refuses_a_sample_time_and_a_torque_constant_of_zero():
    """T > 0 and kt > 0 (each): 0 refused by name, the smallest positive number taken."""
    pd = get_strategy("PDq")
    with refused("T = 0.0 s must be > 0"):
        PositionController(BENCH, pd, T=0.0)
    assert PositionController(BENCH, pd, T=math.ulp(0.0)).T == math.ulp(0.0)
    with refused("kt = (0.5, 0.0) must be > 0"):
        PositionController(BENCH, pd, kt=(0.5, 0.0))
    assert PositionController(BENCH, pd, kt=(0.5, math.ulp(0.0))).kt == (0.5, math.ulp(0.0))


def test_delay_compensation_of_exactly_the_kept_periods_is_taken_and_one_more_refused():
    """delay_compensation in [0, MAX_PREDICT] periods (8: the commands the law's state keeps,
    kernels/src/law.h): (8, 8) is taken, 9 refused, each of angles and rates."""
    assert law.MAX_PREDICT == 8
    pd = get_strategy("PDq")
    assert PositionController(BENCH, pd, delay_compensation=(8, 8)).delay_compensation == (8, 8)
    assert PositionController(BENCH, pd, delay_compensation=(0, 8)).delay_compensation == (0, 8)
    for value in ((9, 0), (0, 9)):
        with refused(f"delay_compensation = {value!r} must be two whole numbers of periods in [0, 8] "
                     "(angles, rates)"):
            PositionController(BENCH, pd, delay_compensation=value)


def test_a_triangle_of_the_most_rounds_the_kernel_takes_is_built_and_one_more_refused():
    """The Trajectory FMU's ``cycles`` of a triangle: MAX_CYCLES (the kernel's limit) is the
    trajectory of that many rounds, MAX_CYCLES + 1 is refused by name; a circle has no such
    limit there."""
    most = from_parameters("triangle", MAX_CYCLES)
    assert most == get_trajectory("triangle", cycles=MAX_CYCLES)
    assert most.duration == pytest.approx(3 * 0.75 * MAX_CYCLES)
    with refused(f"parameter cycles = {MAX_CYCLES + 1} must be <= {MAX_CYCLES} (rounds of the triangle)"):
        from_parameters("triangle", MAX_CYCLES + 1)
    polygon = type(most)
    assert polygon(vertices=most.vertices, side_time=0.75, cycles=1).cycles == 1
    with refused(f"cycles = 0 must be between 1 and {MAX_CYCLES} (rounds of the polygon)"):
        polygon(vertices=most.vertices, side_time=0.75, cycles=0)
