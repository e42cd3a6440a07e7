"""The FMU back end's logger (fmus/cosim/backends.py ``_log``) on its own: each message goes, as
text, to the messages of the instance whose ``componentEnvironment`` it carries, whatever its
category (an FMU may log with a NULL category), undecodable bytes replaced; a message of an
environment no instance registered goes to fmpy's printer with every argument as given.  The
last message is a foreign FMU's refusal in its own words (issue 31: the log was read only
through whole runs whose FMUs log bytes with a category)."""
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
