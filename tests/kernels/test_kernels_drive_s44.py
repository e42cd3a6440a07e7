"""The drive's C step (kernels/src/drive.c) where its branches switch: the measured current
with an offset, a noise, both or neither; the PWM's rounding at the exact half quantum; the
LuGre phi functions on both sides of their series' switch (session 44, training 4411)."""
from __future__ import annotations

import math

import pytest

from motor import Drive, kernel, motor1
from motor.drive import gaussian

H = 1e-3


@pytest.mark.parametrize("offset, noise", [(0.0, 0.0), (0.02, 0.0), (0.0, 0.05), (0.02, 0.05), (-0.03, 0.01)])
def test_the_loop_reads_the_current_plus_its_offset_plus_its_noise_of_the_sample(offset, noise):
    """motor.Drive's docstring: the loop reads i_hat plus the offset plus noise * gaussian(seed,
    instance, k) at controller sample k, whichever of offset and noise is zero.  The error the
    controller keeps (its e1 word) is i_ref minus that, read back each sample (catches the
    shortcut "no offset and no noise: i_hat" taken for another combination, training 4411 [5])."""
    seed, instance = 7, 3
    drive = Drive(motor1, current_offset=offset, current_noise=noise, noise_seed=seed, noise_instance=instance)
    drive.prepare_step(H)
    e1 = kernel.CONTROLLER["e1"].start
    for k in range(5):
        i_ref, i_hat = 0.3 + 0.01 * k, 0.05 * k
        drive.step(i_ref, 0.0, 1.0, i_hat, H)
        measured = i_hat + offset + noise * gaussian(seed, instance, k)
        assert drive._controller_buf[e1] == i_ref - measured, k


@pytest.mark.parametrize("word", ["noise_seed", "noise_instance", "sample"])
def test_a_noise_word_of_two_to_the_64_is_zero_and_the_largest_double_below_it_is_itself(word):
    """drive.c reads the noise's seed, instance and sample count as whole numbers in [0, 2^64)
    (0 outside, where C's conversion is undefined): at 2^64 exactly the noise is that of 0,
    at the largest double below it (2^64 - 2048) the noise is that of that very number (the
    boundary of ``x < 2^64`` met on both sides)."""
    top = 2.0 ** 64
    below = math.nextafter(top, 0.0)
    assert below == 2 ** 64 - 2048
    e1 = kernel.CONTROLLER["e1"].start
    for value, taken in ((top, 0), (below, 2 ** 64 - 2048), (0.0, 0)):
        drive = Drive(motor1, current_noise=0.05, noise_seed=5, noise_instance=2)
        drive.prepare_step(H)
        drive.buf[kernel.DRIVE[word].start] = value
        drive.step(0.0, 0.0, 0.0, 0.0, H)
        words = {"noise_seed": 5, "noise_instance": 2, "sample": 0, word: taken}
        noise = 0.05 * gaussian(words["noise_seed"], words["noise_instance"], words["sample"])
        assert drive._controller_buf[e1] == -(0.0 + 0.0 + noise), value
