"""Every array-level call of the 5R's C kernel (plant/fast5r.py: derivative, actuated
derivative, residual, report, projection, inverse terms) writes exactly its documented words
and reads exactly its documented inputs: each output is followed by sentinel words that must
keep their bits and must itself be written in full, each input by words (NaN, then 0.75) that must not change
an output.  A loop bound one too far (``k <= 2`` over the two chains, ``i <= N_Y``) writes or
reads past a buffer silently in the optimised build; these catch it without the sanitizer."""
from __future__ import annotations

import numpy as np
import pytest

from plant import IntegratorSettings, PlantSimulator, fast5r, get_preset

#: Words past each buffer's end.
GUARD = 5
SENTINEL = -123456.75


def moving_state():
    """A closed, moving 5R state (q, dq: 14 words) of the bench preset, and its packed parameters."""
    sim = PlantSimulator(get_preset("bench"), 0.02, 0.16, IntegratorSettings())
    y = fast5r.project(sim._fast.p, np.concatenate([sim.y[:7], [0.05, -0.04, 0.0, 0.0, 0.0, 0.0, 0.0]]), 3)
    return sim._fast.p, y


def guarded_output(size):
    return np.full(size + GUARD, SENTINEL)


def guarded_input(values, fill):
    return np.concatenate([np.asarray(values, dtype=float), np.full(GUARD, fill)])


def check_written_exactly(out, size, label):
    assert np.all(out[size:] == SENTINEL), f"{label}: words past its {size} were written: {out[size:]}"
    assert not np.any(out[:size] == SENTINEL), f"{label}: a word of its {size} was not written: {out[:size]}"


#: Two motors (joint, R, L, kt, ke, b, mu, omega_eps), as tests/kernels/test_oracles_kernels.py's.
MOTORS = np.array([[0.0, 1.1, 6.7e-4, 0.056, 0.051, 1.2e-4, 0.04, 0.5],
                   [1.0, 2.3, 1.9e-3, 0.081, 0.077, 3.1e-4, 0.02, 0.2]])


def _derivative(p, y, fill):
    out = guarded_output(14)
    fast5r.derivative(p, guarded_input(y, fill), 0.02, -0.03, 50.0, out)
    return out, 14


def _actuated_derivative(p, y, fill):
    z = np.concatenate([y, [0.6, -0.9]])
    out = guarded_output(16)
    voltages = guarded_input([3.0, -5.0], fill)
    fast5r.actuated_derivative(p, MOTORS, guarded_input(z, fill), voltages, 0.02, -0.03, 50.0, out)
    return out, 16


def _residual(p, y, fill):
    out = guarded_output(6)
    fast5r.residual(p, guarded_input(y, fill), out)
    return out, 6


def _report(p, y, fill):
    out = guarded_output(fast5r.REPORT_SIZE)
    fast5r.report(p, guarded_input(y, fill), 1e-4, 2e-3, -3e-3, out)
    return out, fast5r.REPORT_SIZE


def _inverse_terms(p, y, fill):
    out = guarded_output(fast5r.INVERSE_SIZE)
    fast5r.inverse_terms(p, guarded_input(y[:7], fill), guarded_input(y[7:], fill), out)
    return out, fast5r.INVERSE_SIZE


CALLS = {"derivative": _derivative, "actuated_derivative": _actuated_derivative, "residual": _residual,
         "report": _report, "inverse_terms": _inverse_terms}


@pytest.mark.parametrize("name", sorted(CALLS))
def test_each_call_writes_all_its_words_and_no_other_and_reads_only_its_inputs(name):
    """Catches a kernel loop that runs one chain, one state word or one motor too far (a write
    past the caller's buffer, a read of the word after an input) or stops one short (a word of
    the output left unwritten)."""
    p, y = moving_state()
    out, size = CALLS[name](p, y, np.nan)
    check_written_exactly(out, size, name)
    again, _ = CALLS[name](p, y, 0.75)
    assert np.array_equal(again, out), f"{name}: an input word past its end changed an output"


def test_the_projection_changes_only_the_14_state_words():
    """Catches ``pc_fivebar_project`` writing past the state (its chain loop or its rate rows)."""
    p, y = moving_state()
    y[3] += 1e-3                                    # off the manifold: Newton has work to do
    z = np.concatenate([y, np.full(GUARD, SENTINEL)])
    fast5r._project(fast5r._address(p), fast5r._address(z), 3)
    assert np.all(z[14:] == SENTINEL)
    assert np.all(np.isfinite(z[:14])) and not np.array_equal(z[:14], y)


def test_each_newton_iteration_of_the_projection_counts():
    """pc_fivebar_project from a state whose four joint angles are 2e-3 rad off closure, x and y
    kept: 0 iterations leave the angles, each iteration then cuts the loop-closure residual
    (5.18) of both chains quadratically (below 1e-5 m after one, 1e-10 m after two).  Catches an iteration loop that starts at 1 or stops one
    short (the residual of one iteration fewer), or one chain left out of it."""
    p, y = moving_state()
    off = y.copy()
    off[[3, 4, 5, 6]] += [2e-3, -2e-3, 1.5e-3, 2e-3]
    res = np.empty(6)
    norms = []
    for iterations in range(4):
        projected = fast5r.project(p, off.copy(), iterations)
        fast5r.residual(p, projected, res)
        norms.append(float(np.linalg.norm(res)))
        assert projected[:2].tolist() == off[:2].tolist()
        if iterations == 0:
            assert projected[3:7].tolist() == off[3:7].tolist()
    assert norms[0] > 1e-4 and norms[1] < 1e-5 and norms[2] < 1e-10 and norms[3] <= norms[2]


def test_a_step_is_refused_as_singular_only_below_the_margin_not_at_it():
    """plant/simulator.py: below SINGULAR_STOP the step is refused (``abs(value) < SINGULAR_STOP``):
    pc_fivebar_step with the stop set to a measure of its own trial state exactly accepts the
    step; the next double above refuses it with SINGULAR, that measure's index and value
    (training seed 4251 [4]: ``<=`` passed; the 14 states of the bench preset give the three
    measures away from 0)."""
    p, y = moving_state()
    kernel = fast5r.FastKernel(get_preset("bench"), fast5r.pack_settings(0.0, 1, 1.0, np.inf, 0.0))
    assert np.array_equal(kernel.p, p)
    assert kernel.step(y, 0.01, -0.02, 1e-3) == fast5r.OK
    measures = kernel.report[fast5r.REPORT_MEASURES:fast5r.REPORT_MEASURES + 3].copy()
    smallest = int(np.argmin(np.abs(measures)))
    stop = abs(measures[smallest])
    kernel.s[fast5r.S_SINGULAR_STOP] = stop
    assert kernel.step(y, 0.01, -0.02, 1e-3) == fast5r.OK
    kernel.s[fast5r.S_SINGULAR_STOP] = np.nextafter(stop, np.inf)
    assert kernel.step(y, 0.01, -0.02, 1e-3) == fast5r.SINGULAR
    r = kernel.refusal
    assert (r.code, r.index, r.value) == (fast5r.SINGULAR, smallest, measures[smallest])


def test_a_step_is_refused_as_diverged_only_above_the_residual_stop_not_at_it():
    """plant/simulator.py: a step whose residual is above RESIDUAL_STOP is refused; at it exactly
    the step is taken, one double below it refuses it with DIVERGED, index 0 and the residual
    (the sibling of the singular margin's boundary above)."""
    p, y = moving_state()
    kernel = fast5r.FastKernel(get_preset("bench"), fast5r.pack_settings(0.0, 1, 1.0, np.inf, 0.0))
    assert kernel.step(y, 0.01, -0.02, 1e-3) == fast5r.OK
    residual = kernel.report[fast5r.REPORT_RESIDUAL]
    assert 0.0 < residual < 1e-6
    kernel.s[fast5r.S_RESIDUAL_STOP] = residual
    assert kernel.step(y, 0.01, -0.02, 1e-3) == fast5r.OK
    kernel.s[fast5r.S_RESIDUAL_STOP] = np.nextafter(residual, -np.inf)
    assert kernel.step(y, 0.01, -0.02, 1e-3) == fast5r.DIVERGED
    r = kernel.refusal
    assert (r.code, r.index, r.value) == (fast5r.DIVERGED, 0, residual)
