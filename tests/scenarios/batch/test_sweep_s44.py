"""scenarios/batch/sweep.py's files at their boundaries, without running a sweep (issue 31,
session 44: the boundaries of the generalised training sample hit exactly)."""
from __future__ import annotations

import math
import os

from scenarios.batch import sweep

HEADER = sweep.columns(["drive1.R"])


def _write(path, values):
    appender = sweep._Appender(path, HEADER)
    for k, value in enumerate(values):
        appender.append({"sample": k, "drive1.R": value, **{m: 0.5 for m in sweep.METRICS}, "completed": True,
                         "outcome": "completed", "error_instance": "", "error_time": math.nan,
                         "error_variable": "", "error_value": math.nan, "error_unit": "", "error_code": None,
                         "error_reason": "", "error": "", "wall_s": 1.0})
    appender.close()


def test_repairing_a_file_whose_last_row_is_whole_leaves_the_file_untouched(tmp_path):
    """A file that ends with its last row's newline has nothing torn to cut: ``repair`` reads it
    and writes nothing (its bytes and its modification time stay).  Catches the cut made
    also when the last newline is the file's last byte (``<=`` for ``<``)."""
    path = tmp_path / "sweep.csv"
    _write(path, [1.25, 1.5])
    data = path.read_bytes()
    assert data.endswith(b"\n")
    os.utime(path, (1_000_000, 1_000_000))
    rows = sweep.read_rows(path, HEADER, repair=True)
    assert [r["drive1.R"] for r in rows] == [1.25, 1.5]
    assert path.read_bytes() == data and path.stat().st_mtime == 1_000_000


def test_repairing_a_file_torn_one_byte_after_its_last_newline_cuts_that_byte(tmp_path):
    """One byte past the last whole row is a torn row: cut off, the whole rows kept."""
    path = tmp_path / "sweep.csv"
    _write(path, [1.25])
    data = path.read_bytes()
    path.write_bytes(data + b"2")
    assert [r["drive1.R"] for r in sweep.read_rows(path, HEADER, repair=True)] == [1.25]
    assert path.read_bytes() == data
