"""The limits of a serialised state (fmus/slave/state_format.py) are the ones docs/state.md gives
a native FMU to write and read by (issue 31, session 44: the boundary tests of
test_fmu_state_format.py take the limits from the module itself, so a limit changed in the
module passed them; here they are read from the documentation).

"Nesting is limited to 64 levels, a state to 2^24 values and 1 GiB"; an array has "u8 ndim (≤ 8)";
the dtypes the bytes alone may name are listed.  The nesting limit is also hit at the documented
depth itself: 64 levels written and read back, 65 refused by writer and reader.
"""
from __future__ import annotations

import re

import numpy as np
import pytest

from fmus.slave import state_format as sf
from tests.support.paths import ROOT

DOC = (ROOT / "docs" / "state.md").read_text(encoding="utf-8")
HEADER = sf.Header(model="M", guid="", config=bytes(32), layout=1)


def test_the_nesting_value_and_byte_limits_are_the_documented_ones():
    depth, power, gib = re.search(r"Nesting is limited to (\d+) levels, a state to 2\^(\d+) values and (\d+) GiB",
                                  " ".join(DOC.split())).groups()
    assert (sf.MAX_DEPTH, sf.MAX_VALUES, sf.MAX_BYTES) == (int(depth), 2 ** int(power), int(gib) * 2 ** 30)


def test_an_arrays_dimensions_are_limited_as_documented():
    (most,) = re.search(r"u8 ndim \(≤ (\d+)\)", DOC).groups()
    assert sf.MAX_NDIM == int(most)


def test_the_dtypes_the_bytes_alone_name_are_the_documented_list():
    listed = re.search(r"Array dtypes that the bytes alone may name are ([^.]*)\.", " ".join(DOC.split())).group(1)
    documented = {np.dtype(t.strip("`")).str for t in listed.split()}
    assert set(sf.PLAIN_DTYPES) == documented and len(documented) == 13


def _nested(depth: int):
    value = 0.5
    for _ in range(depth):
        value = [value]
    return value


def test_a_value_64_levels_deep_is_written_and_read_back_and_65_is_refused():
    """The top value is at depth 0 (docs/state.md's 64 levels, counted here without the module's
    constant)."""
    header, value = sf.decode(sf.encode(HEADER, _nested(64)))
    assert value == _nested(64)
    with pytest.raises(ValueError, match="^the state is nested deeper than 64 levels$"):
        sf.encode(HEADER, _nested(65))
