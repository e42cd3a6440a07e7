"""The words of a kernel buffer a run changes (``KERNEL_BUFFERS``' ``run_state_words``, which a
restored FMU state may change while every other word is configuration, fmus/slave/state.py),
held against what a run actually changes: the derivator's (controller/fastderivator.py) and the
balance controller's (controller/fastbalance.py) buffers compared word by word before and after
steps with varying inputs."""
from __future__ import annotations

import math

import numpy as np
import pytest

import kernels
from controller import fastbalance, fastderivator
from controller.derivators import Derivator


def _changed(before, after):
    return set(np.flatnonzero(~((before == after) | (np.isnan(before) & np.isnan(after)))).tolist())


@pytest.mark.parametrize("channels", [1, 2, 3])
@pytest.mark.parametrize("T", [1e-3, 2e-3])
def test_the_derivators_run_state_is_exactly_what_its_steps_change(channels, T):
    """From its first sample on, 40 steps of distinct angles per channel change exactly
    ``run_state_words``: the start flag and every filter state word, nothing else (the sizes,
    1/T and the sections stay).  Catches a run state that is empty or short (a restored
    state refused as a changed configuration) or that takes configuration words in."""
    d = Derivator(T=T)
    d.start_at_first_sample(channels)
    kept = d.buf.copy()
    rng = np.random.default_rng(channels)
    for k in range(40):
        d.step(0.3 * np.sin(0.05 * k + np.arange(channels)) + rng.normal(0.0, 1e-3, channels))
    words = set(fastderivator.run_state_words(d.buf))
    assert Derivator.KERNEL_BUFFERS["buf"] is fastderivator.run_state_words
    assert fastderivator.V_STARTED in words
    assert len(words) == 1 + (d.buf.size - min(words - {fastderivator.V_STARTED}))
    assert _changed(kept, d.buf) == words


def test_the_balance_run_state_is_exactly_what_its_samples_change():
    """The balance buffer's run state (started, the kept states' estimate, the two voltages)
    against 30 samples of a tilting, turning start: the words changed are inside it, and every
    word of it a run can change did change (estimate words past the kept states stay 0)."""
    from controller.balance import BalanceController, BalanceSettings, design_balance, get_route

    controller = BalanceController(design_balance(BalanceSettings(yaw=True)), get_route("forward_turn"))
    buf, x = controller.buf.copy(), np.zeros(fastbalance.IO_SIZE)
    kept = buf.copy()
    for k in range(30):
        x[:3] = 0.01 * k, 0.012 * k, -0.2 + 0.01 * math.sin(k)
        assert fastbalance.sample(buf, x, 0.01 * k, 1e6, kernels.Refusal()) == fastbalance.OK
    words = set(fastbalance.run_state_words(buf))
    n = len(controller.design.states)
    live = {fastbalance.B_STARTED, fastbalance.B_U, fastbalance.B_U + 1} | \
        set(range(fastbalance.B_X_HAT, fastbalance.B_X_HAT + n))
    assert _changed(kept, buf) == live and live <= words


def test_the_balance_run_state_is_the_state_struct_and_no_configuration_word():
    """``pc_balance_state`` (kernels/src/balance.h): started, x_hat, u, all of them and no
    word of ``pc_balance_params`` (sizes, gains, matrices), which a restored FMU state may
    not change."""
    layout = fastbalance.BUFFER
    state = {k for name in ("started", "x_hat", "u") for k in range(layout[name].start, layout[name].stop)}
    configuration = {k for name in ("n", "ny", "yaw", "K", "Lo", "C", "Ad", "Bd")
                     for k in range(layout[name].start, layout[name].stop)}
    words = fastbalance.run_state_words(np.zeros(fastbalance.BUF_SIZE))
    assert set(words) == state and len(words) == len(state)
    assert not set(words) & configuration
