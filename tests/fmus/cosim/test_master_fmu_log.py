"""The FMU back end (fmus/cosim/backends.py) without an FMU.  Its logger ``_log``: each message goes,
as text, to the messages of the instance whose ``componentEnvironment`` it carries, whatever its
category (an FMU may log with a NULL category), undecodable bytes replaced; a message of an
environment no instance registered goes to fmpy's printer with every argument as given.  The last
message is a foreign FMU's refusal in its own words.  Its ``set_inputs`` through a stand-in
library: one call a type, a warning no refusal, a refusal in the FMU's last words or "setting
inputs failed" (issue 31: the log was read only through whole runs whose FMUs log bytes with a
category; a refused set of inputs ran in no test)."""
from __future__ import annotations

import pytest

from fmus.cosim import backends


@pytest.fixture
def environment(monkeypatch):
    """A registered environment and its messages (taken back after the test)."""
    messages = []
    monkeypatch.setitem(backends._LOGS, -17, messages)
    return -17, messages


@pytest.mark.parametrize("category", [b"logStatusError", None, b""])
def test_a_message_is_its_instances_text_whatever_its_category(environment, category):
    """Catches the message decoded only when the category is bytes (a NULL category then logs
    "b'...'"), the category logged in place of the message, or bytes kept as bytes."""
    env, messages = environment
    backends._log(env, b"drive1", 3, category, b"the step 0.001 s must divide T = 0.0025 s")
    backends._log(env, b"drive1", 3, category, "already text")
    backends._log(env, b"drive1", 3, category, b"bad \xff byte")
    assert messages == ["the step 0.001 s must divide T = 0.0025 s", "already text", "bad \ufffd byte"]


def test_a_message_of_an_unknown_environment_goes_to_fmpys_printer(environment, monkeypatch):
    """Catches another FMU's message (fmpy's own callbacks share the proxy) put in an instance's
    messages, or passed on with its arguments changed."""
    import fmpy.fmi2

    printed = []
    monkeypatch.setattr(fmpy.fmi2, "printLogMessage", lambda *args: printed.append(args))
    env, messages = environment
    backends._log(env + 1, b"other", 1, b"logAll", b"hello")
    assert printed == [(env + 1, b"other", 1, b"logAll", b"hello")] and messages == []


class _Library:
    """An FMU library's ``fmi2Set*`` as the step path calls them: the values each call got, and the
    status to answer (0 OK, 1 warning, 3 error)."""

    def __init__(self, status: int):
        self.status, self.got = status, []

    def _set(self, kind):
        def call(component, vrs, n, array):
            self.got.append((kind, list(vrs), n.value, list(array)))
            return self.status
        return call

    def __getattr__(self, name):
        if name.startswith("fmi2Set"):
            return self._set(name[len("fmi2Set"):])
        raise AttributeError(name)


def _instance(status: int, messages: list, variables: list):
    """An ``_FmuInstance`` whose library is :class:`_Library` (nothing loaded)."""
    instance = object.__new__(backends._FmuInstance)
    instance.name, instance.messages, instance._component = "drive1", messages, None
    library = _Library(status)
    instance._inputs = backends._Batch(variables, library, "Set")
    return instance, library


REAL = [backends.Variable(name, vr, "Real", "input", "continuous") for name, vr in (("u", 3), ("w", 7))]
MIXED = [REAL[0], backends.Variable("k", 4, "Integer", "input", "continuous"), REAL[1]]


@pytest.mark.parametrize("status", [0, 1])
def test_inputs_are_set_in_one_call_per_type_and_a_warning_is_no_refusal(status):
    """Catches a warning taken for a refusal, and values sent to other references or unconverted."""
    instance, library = _instance(status, [], MIXED)
    instance.set_inputs([1.5, 2.0, -3.25])
    assert library.got == [("Real", [3, 7], 2, [1.5, -3.25]), ("Integer", [4], 1, [2])]


@pytest.mark.parametrize("messages, said", [(["first", "the FMU's words"], "the FMU's words"),
                                            ([], "setting inputs failed")])
def test_a_refused_set_of_inputs_says_the_fmus_last_words_or_that_setting_failed(messages, said):
    """fmi2Error from fmi2SetReal: a CoSimulationError of the instance with the FMU's last log
    message, or "setting inputs failed" when it logged none.  Catches the fallback words lost (an
    empty message) or replacing the FMU's own."""
    instance, _ = _instance(3, messages, REAL)
    with pytest.raises(backends.CoSimulationError) as refused:
        instance.set_inputs([1.0, 2.0])
    assert (refused.value.instance, refused.value.message) == ("drive1", said)
