"""The master's SIGINT rule (:func:`fmus.cosim.master.deferred_sigint`): in the main thread under
Python's default handler, the first SIGINT only asks the run to stop between steps and a second
one interrupts at once, and the default handler is back afterwards; in another thread, or under
a handler someone else installed, nothing changes (that handler stays, inside and after)."""
from __future__ import annotations

import signal
import threading

import pytest

from fmus.cosim.master import deferred_sigint


@pytest.fixture
def default_handler():
    """Python's default SIGINT handler for the test; the one before it restored afterwards."""
    before = signal.getsignal(signal.SIGINT)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, before)


def test_the_first_sigint_is_deferred_and_the_second_interrupts(default_handler):
    with pytest.raises(KeyboardInterrupt):
        with deferred_sigint() as interrupt:
            assert not interrupt.requested
            signal.raise_signal(signal.SIGINT)
            assert interrupt.requested                 # noted, nothing raised
            signal.raise_signal(signal.SIGINT)         # the second: at once
            pytest.fail("a second SIGINT did not interrupt")
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_a_handler_someone_else_installed_is_kept_inside_and_after(default_handler):
    """Catches the rule applied when only one of its two conditions holds: the caller's handler
    replaced inside and Python's default left in its place afterwards."""
    seen = []

    def theirs(signum, frame):
        seen.append(signum)

    signal.signal(signal.SIGINT, theirs)
    with deferred_sigint() as interrupt:
        assert signal.getsignal(signal.SIGINT) is theirs
        signal.raise_signal(signal.SIGINT)
    assert signal.getsignal(signal.SIGINT) is theirs
    assert seen == [signal.SIGINT] and not interrupt.requested


def test_outside_the_main_thread_nothing_is_installed(default_handler):
    """Only the main thread may install a handler (signal.signal raises ValueError elsewhere):
    a run in a worker thread goes ahead under the default handler, untouched."""
    got = []

    def run():
        try:
            with deferred_sigint() as interrupt:
                got.append((interrupt.requested, signal.getsignal(signal.SIGINT)))
        except Exception as exc:  # noqa: BLE001 - the test reports it
            got.append(exc)

    worker = threading.Thread(target=run)
    worker.start()
    worker.join()
    assert got == [(False, signal.default_int_handler)]
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
