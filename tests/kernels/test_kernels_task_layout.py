"""plant/kinematics5r.py's ctypes ``Task`` is written by hand; the library exports the C struct
``pc_5r_task``'s own field list (``pc_5r_task_fields``, the one controller/law.py reads).  Every
field of the Python struct must sit at the C field's offset with its size."""
from __future__ import annotations

import ctypes

import kernels
from plant import kinematics5r as k5r


def test_the_python_task_struct_is_the_c_layout_field_by_field():
    """Catches a field of the Python Task of another length (an array of 4 for 2) or order, which
    shifts every field after it: J, beta or the distance read from another field's words."""
    layout = kernels.layout("pc_5r_task_fields")
    fields = [name for name, _ in k5r.Task._fields_]
    assert fields == list(layout)
    for name in fields:
        place = getattr(k5r.Task, name)
        words = layout[name]
        assert (place.offset, place.size) == (8 * words.start, 8 * (words.stop - words.start)), name
    assert ctypes.sizeof(k5r.Task) == 8 * kernels.size(layout)

