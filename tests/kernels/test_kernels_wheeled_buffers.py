"""The wheeled pendulum's binding (plant/wheeled_kernel.py) checks every buffer it hands the C
kernel: each one of each call, one word short or of another type, is refused by size before C
reads it (nothing written), and the same call with whole buffers goes through."""
from __future__ import annotations

import numpy as np
import pytest

import kernels
from plant import wheeled_kernel as K
from plant.wheeled import SEED, pack

N_X = len(K.INPUT_NAMES) + len(K.OUTPUT_NAMES)


def _settings():
    return K.new_settings(substeps=2, count=2 * np.pi / 2048, push_torque=0.0, push_start=0.0,
                          push_duration=0.0, limit=10.0)


def _state():
    y = np.zeros(K.N_STATE)
    y[K.PSI], y[K.DTHETA] = 0.05, 0.3
    return y


#: name -> (the call of the buffers, the buffers in order, each one's size)
CALLS = {
    "derivative": (lambda prm, y, out: K.derivative(prm, y, 0.01, -0.02, 0.0, out), (K.PARAMS_SIZE, K.N_STATE, K.N_STATE)),
    "condition": (lambda prm, y: K.condition(prm, y), (K.PARAMS_SIZE, K.N_STATE)),
    "energy": (lambda prm, y: K.energy(prm, y), (K.PARAMS_SIZE, K.N_STATE)),
    "sensors": (lambda prm, y, out: K.sensors(prm, y, 0.001, out), (K.PARAMS_SIZE, K.N_STATE, len(K.OUTPUT_NAMES))),
    "step_io": (lambda prm, y, s, x: K.step_io(prm, y, s, x, 0.0, 1e-3, kernels.Refusal()),
                (K.PARAMS_SIZE, K.N_STATE, K.SETTINGS_SIZE, N_X)),
}


def _buffers(sizes):
    whole = [pack(SEED), _state()] + [np.zeros(n) for n in sizes[2:]]
    if len(sizes) == 4:
        whole[2] = _settings()
    return whole


@pytest.mark.parametrize("name", sorted(CALLS))
def test_every_buffer_of_every_call_is_checked_before_the_kernel_reads_it(name):
    """Catches a binding that leaves a buffer out of its check (C would read past a short state
    or parameter array, or take an int array's words as doubles), or checks it against
    another's size."""
    call, sizes = CALLS[name]
    call(*_buffers(sizes))                                   # whole buffers: accepted
    converts_state = name == "derivative"                    # it makes y a float array itself
    for k, size in enumerate(sizes):
        wrong = [np.zeros(size - 1)]
        if not (converts_state and k == 1):
            wrong += [np.zeros(size, dtype=np.float32), np.zeros(size, dtype=np.int64), [0.0] * size]
        for bad in wrong:
            buffers = _buffers(sizes)
            kept = [np.array(b, copy=True) for b in buffers]
            buffers[k] = bad
            with pytest.raises(ValueError, match=rf"^a wheeled-pendulum kernel buffer must be a float64 array "
                                                 rf"of >= {size} words$"):
                call(*buffers)
            for j, (before, after) in enumerate(zip(kept, buffers)):
                if j != k:
                    assert np.array_equal(before, after), (name, k, j)     # nothing written


def test_a_longer_buffer_is_read_only_up_to_its_size():
    """Catches a check that wants the exact size (``==`` for ``>=``): a state with spare words is
    accepted and gives the energy of its first N_STATE."""
    prm, y = pack(SEED), _state()
    assert K.energy(prm, np.concatenate([y, [np.nan, 1e300]])) == K.energy(prm, y)


def test_settings_are_built_by_name_each_at_its_word_and_a_missing_or_unknown_name_is_refused():
    """Catches a settings buffer that puts a value at another field's word, or accepts a call
    that leaves a field out (its word uninitialised) or names one the kernel has not, when
    the other mistake is absent."""
    names = list(K.SETTINGS)
    values = {name: 0.5 + k for k, name in enumerate(names)}
    settings = K.new_settings(**values)
    assert settings.size == K.SETTINGS_SIZE
    for name, value in values.items():
        assert np.all(settings[K.SETTINGS[name]] == value), name
    listed = ", ".join(names)
    short = dict(values)
    del short[names[1]]
    with pytest.raises(ValueError) as caught:
        K.new_settings(**short)
    assert str(caught.value) == f"the pendulum's settings are {listed}: missing {[names[1]]}, unknown []"
    with pytest.raises(ValueError) as caught:
        K.new_settings(**values, gain=2.0)
    assert str(caught.value) == f"the pendulum's settings are {listed}: missing [], unknown ['gain']"


@pytest.mark.parametrize("index", [0, 1, 2])
def test_a_torque_at_the_input_limit_is_taken_and_one_double_beyond_is_refused_naming_it(index):
    """pc_wheeled_step_io checks |tau| <= limit (the settings' limit, 10 N m here): a torque of
    magnitude exactly the limit is taken, either sign; the next double beyond is refused as
    INPUT_LIMIT naming that input (tau_l, tau_r, tau_d) and its value, the state unchanged."""
    for sign in (1.0, -1.0):
        prm, y, s = pack(SEED), _state(), _settings()
        x, refusal = np.zeros(N_X), kernels.Refusal()
        x[index] = sign * 10.0
        assert K.step_io(prm, y, s, x, 0.0, 1e-4, refusal) == K.OK
        y, x = _state(), np.zeros(N_X)
        x[index] = sign * np.nextafter(10.0, np.inf)
        assert K.step_io(prm, y, s, x, 0.0, 1e-4, refusal) == K.INPUT_LIMIT
        assert (refusal.index, refusal.value) == (index, x[index])
        np.testing.assert_array_equal(y, _state())
