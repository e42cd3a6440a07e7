"""plant/fast5r.py's named places in the C kernel's settings and report buffers
(``S_*``, ``REPORT_*``): each names the word its comment says, read back through the kernel.
Session 44, training sample 4421 [17]: ``S_OFFSET2`` pointing at another settings word went
unseen, since nothing read the encoder offsets through the names."""
from __future__ import annotations

import math

import numpy as np
import pytest

import kernels
from plant import PlantSimulator, fast5r, get_preset
from plant.fast5r import FastKernel


def test_each_named_settings_word_holds_its_pack_settings_argument_and_all_words_are_named():
    """pack_settings(lambda, substeps, count, residual_stop, singular_stop, (offset1, offset2)),
    seven distinct values: each name reads back its own, and the seven names are the seven
    words of the buffer (no two names on one word)."""
    values = dict(lam=7.5, substeps=3, count=2.5e-3, residual_stop=4e-4, singular_stop=6e-3,
                  offsets=(0.125, -0.375))
    s = fast5r.pack_settings(values["lam"], values["substeps"], values["count"], values["residual_stop"],
                             values["singular_stop"], values["offsets"])
    names = {fast5r.S_LAMBDA: 7.5, fast5r.S_SUBSTEPS: 3.0, fast5r.S_COUNT: 2.5e-3, fast5r.S_RESIDUAL_STOP: 4e-4,
             fast5r.S_SINGULAR_STOP: 6e-3, fast5r.S_OFFSET1: 0.125, fast5r.S_OFFSET2: -0.375}
    assert sorted(names) == list(range(fast5r.SETTINGS_SIZE)) == list(range(7))
    for word, value in names.items():
        assert s[word] == value, word


def test_the_encoder_offsets_at_their_named_words_move_each_encoder_reading():
    """The kernel's report (``pc_fivebar_report_of``) reads encoder j's zero error from the
    word named S_OFFSETj: with count 1e-3 rad and offsets (0.25, -0.125) rad written there,
    q_j_enc = count round((q_j + offset_j) / count), q1 = y[3], q2 = pi - y[5] (the world
    angles), and the other outputs are the state's."""
    sim = PlantSimulator(get_preset("bench"), 0.01, 0.15, dx0=0.2, dy0=-0.1)
    y = sim.y
    count, offsets = 1e-3, (0.25, -0.125)
    s = fast5r.pack_settings(0.0, 1, count, math.inf, 0.0)
    s[fast5r.S_OFFSET1], s[fast5r.S_OFFSET2] = offsets
    kernel = FastKernel(get_preset("bench"), s)
    report = np.empty(fast5r.REPORT_SIZE)
    kernel_report = kernels_report(kernel, y, report)
    q1, q2 = y[3], math.pi - y[5]
    outputs = kernel_report[fast5r.REPORT_OUTPUTS:fast5r.REPORT_OUTPUTS + 10]
    assert outputs[:8].tolist() == [q1, q2, y[10], -y[12], y[0], y[1], y[7], y[8]]
    for q, offset, reading in zip((q1, q2), offsets, outputs[8:]):
        assert reading == pytest.approx(count * math.floor((q + offset) / count + 0.5), abs=1e-15)
    assert abs(outputs[8] - q1) > 0.2 and abs(outputs[9] - q2) > 0.1      # each offset seen in its own reading
    assert kernel_report[fast5r.REPORT_FINITE] == 1.0
    res = np.empty(6)
    fast5r.residual(kernel.p, y, res)
    assert kernel_report[fast5r.REPORT_RESIDUAL] == pytest.approx(float(np.linalg.norm(res)), rel=1e-12, abs=1e-18)
    assert fast5r.REPORT_SIZE == fast5r.REPORT_OUTPUTS + 10 == fast5r.REPORT_MEASURES + 13



def kernels_report(kernel, y, out):
    """The report of y under the kernel's own settings buffer (``pc_fivebar_report_of``, as
    fast5r binds it)."""
    y = np.ascontiguousarray(y, dtype=np.float64)
    fast5r._report(kernels.address(kernel.p), kernels.address(kernel.s), kernels.address(y), kernels.address(out))
    return out
