"""``simulate_ssp_libcosim(..., isolated=True)`` (fmus/ssp/libcosim.py ``_isolated``) with the child
process replaced by a stand-in interpreter (no libcosim needed): a child that dies before writing
its result is a RuntimeError naming its exit status and the last five lines of what it wrote
(stderr, else stdout), its output passed on; a result it wrote is returned with the child's exit
status in ``extra``, an exception it wrote is raised (issue 31: the crash's message was read only
through a real abort, whose output's length nothing fixed)."""
from __future__ import annotations

import pickle
import sys
import textwrap

import numpy as np
import pytest

from fmus.ssp import libcosim
from fmus.ssp.run import SspRun

#: The interpreter the stand-in runs on (``sys.executable`` is the stand-in during a test).
PYTHON = sys.executable


def _child(tmp_path, monkeypatch, body: str):
    """Make ``body`` (Python; ``result`` is the path the parent reads) the child's interpreter."""
    script = tmp_path / "python"
    script.write_text(f"#!{PYTHON}\nimport sys\nresult = sys.argv[-1]\n" + textwrap.dedent(body))
    script.chmod(0o755)
    monkeypatch.setattr(libcosim.sys, "executable", str(script))


def test_a_child_dying_without_a_result_is_an_error_with_its_last_five_lines(tmp_path, monkeypatch, capsys):
    """Catches another number of lines kept, the first lines kept instead of the last, stdout
    preferred to stderr, the exit status not named, and the child's output swallowed."""
    _child(tmp_path, monkeypatch, """
        print("out line")
        for k in range(1, 13):
            print(f"err {k}", file=sys.stderr)
        sys.exit(3)
    """)
    with pytest.raises(RuntimeError) as failed:
        libcosim.simulate_ssp_libcosim(tmp_path / "x.ssp", ["a.y"], isolated=True)
    assert str(failed.value) == ("libcosim's process ended with exit status 3 before it had a result: "
                                 "err 8\nerr 9\nerr 10\nerr 11\nerr 12")
    seen = capsys.readouterr()
    assert seen.out == "out line\n" and seen.err.splitlines() == [f"err {k}" for k in range(1, 13)]


def test_without_stderr_the_tail_is_stdouts_and_without_output_there_is_none(tmp_path, monkeypatch):
    """Catches stdout's tail not taken when stderr is empty, and a dangling ": " without output."""
    _child(tmp_path, monkeypatch, """
        print("\\n".join(f"o{k}" for k in range(7)))
        sys.exit(4)
    """)
    with pytest.raises(RuntimeError) as failed:
        libcosim.simulate_ssp_libcosim(tmp_path / "x.ssp", ["a.y"], isolated=True)
    assert str(failed.value).endswith("exit status 4 before it had a result: o2\no3\no4\no5\no6")
    _child(tmp_path, monkeypatch, "sys.exit(5)\n")
    with pytest.raises(RuntimeError) as failed:
        libcosim.simulate_ssp_libcosim(tmp_path / "x.ssp", ["a.y"], isolated=True)
    assert str(failed.value) == "libcosim's process ended with exit status 5 before it had a result"


def test_a_result_written_is_returned_with_the_exit_status_and_an_exception_is_raised(tmp_path, monkeypatch):
    """The child's arguments: the package's resolved path, the signals and the keywords.  Catches
    them not passed, the exit status of a child that crashed after writing not kept in ``extra``,
    and an exception the child wrote returned instead of raised."""
    run = SspRun(time=np.arange(2) * 1e-3, signals={"a.y": np.ones(2)}, tool="libcosim", wall_s=0.0)
    (tmp_path / "run.pickle").write_bytes(pickle.dumps(run))
    _child(tmp_path, monkeypatch, f"""
        import pickle, shutil
        args = pickle.loads(open(sys.argv[-2], "rb").read())
        open({str(tmp_path / 'args.txt')!r}, "w").write(repr(args))
        shutil.copy({str(tmp_path / 'run.pickle')!r}, result)
        sys.exit(-6 % 256)
    """)
    got = libcosim.simulate_ssp_libcosim(tmp_path / "x.ssp", ["a.y"], step_size=2e-3, isolated=True)
    assert np.array_equal(got.time, run.time) and got.extra["exit_status"] == 250
    path, signals, kwargs = eval((tmp_path / "args.txt").read_text())
    assert (path, signals) == (str((tmp_path / "x.ssp").resolve()), ["a.y"])
    assert kwargs == {"stop_time": None, "step_size": 2e-3, "log_level": "warning", "worker_threads": 0}
    (tmp_path / "run.pickle").write_bytes(pickle.dumps(ValueError("from the child")))
    with pytest.raises(ValueError, match="^from the child$"):
        libcosim.simulate_ssp_libcosim(tmp_path / "x.ssp", ["a.y"], isolated=True)
