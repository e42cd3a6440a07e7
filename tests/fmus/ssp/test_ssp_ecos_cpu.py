"""``fmus.ssp.run._one_cpu``, around Ecos's first step: the calling thread bound to one CPU of
those it had (the lowest), only when asked, and its own mask, whatever it was, restored after
the block, also when the block raises (issue 31: a mask read from another process, or set
when not asked, changed no result of a run here)."""
from __future__ import annotations

import os

import pytest

from fmus.ssp.run import _one_cpu

pytestmark = pytest.mark.skipif(not hasattr(os, "sched_getaffinity") or len(os.sched_getaffinity(0)) < 2,
                                reason="needs CPU affinity and two CPUs")


@pytest.fixture
def mask():
    """Sets the calling thread's mask (``mask(cpus)``) and puts the old one back after."""
    before = os.sched_getaffinity(0)
    yield lambda cpus: os.sched_setaffinity(0, cpus) or set(cpus)
    os.sched_setaffinity(0, before)


def test_the_block_runs_on_the_lowest_cpu_and_the_whole_mask_comes_back(mask):
    """Catches another CPU taken, the mask not restored after the block or after an
    exception in it, and the thread bound when the caller did not ask."""
    every = mask(os.sched_getaffinity(0))
    with _one_cpu(True):
        assert os.sched_getaffinity(0) == {min(every)}
    assert os.sched_getaffinity(0) == every
    with pytest.raises(RuntimeError), _one_cpu(True):
        raise RuntimeError("a failed step")
    assert os.sched_getaffinity(0) == every
    with _one_cpu(False):
        assert os.sched_getaffinity(0) == every
    assert os.sched_getaffinity(0) == every


def test_the_cpu_is_one_of_the_threads_own_mask(mask):
    """The thread bound to the highest CPU only (a mask no other process has): the block
    stays there.  Catches the mask read from another process (pid 1's, all CPUs)."""
    own = mask({max(os.sched_getaffinity(0))})
    with _one_cpu(True):
        assert os.sched_getaffinity(0) == own
    assert os.sched_getaffinity(0) == own
