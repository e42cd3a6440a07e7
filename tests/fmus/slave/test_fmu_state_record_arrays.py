"""A record array in a state (:func:`fmus.slave.state.apply`): read as raw bytes with its dtype's
key (:class:`fmus.slave.state_format.ArrayBytes`), laid back into the live instance's array of
that dtype when the byte count is its shape times the item size, exactly; refused naming the
count and the shape otherwise."""
from __future__ import annotations

import numpy as np
import pytest

from fmus.slave import state as fmustate
from fmus.slave import state_format as sf

DTYPE = [("a", "<f8"), ("b", "<i4")]


def _template():
    return {"r": np.zeros(2, dtype=DTYPE)}


def test_a_record_array_is_read_back_into_the_instances_array_exactly():
    saved = np.array([(1.5, -2), (3.0, 7)], dtype=DTYPE)
    template = _template()
    live = template["r"]
    got = fmustate.apply(template, {"r": sf.ArrayBytes(sf.dtype_key(saved.dtype), (2,), saved.tobytes())})
    assert got["r"] is live and live.tobytes() == saved.tobytes()


@pytest.mark.parametrize("cut", [-1, 1])
def test_a_record_array_whose_bytes_do_not_fill_its_shape_is_refused(cut):
    saved = np.array([(1.5, -2), (3.0, 7)], dtype=DTYPE)
    raw = saved.tobytes()
    raw = raw[:cut] if cut < 0 else raw + b"\0" * cut
    with pytest.raises(fmustate.StateMismatch, match=rf"^r: {len(raw)} bytes for an array of shape \(2,\)$"):
        fmustate.apply(_template(), {"r": sf.ArrayBytes(sf.dtype_key(saved.dtype), (2,), raw)})
