"""The in-process master with every slave through its Python ``do_step`` (its stepper without
the kernel segments of :mod:`fmus.cosim.segments`): the independent path that the segments'
rows, records and states are compared with."""
from __future__ import annotations

from contextlib import contextmanager

from fmus.cosim import master


@contextmanager
def python_slaves():
    """Within the block, ``simulate(mode="inprocess")`` steps every slave in Python."""
    original = master.Stepper

    class PythonStepper(original):
        def __init__(self, *args, kernels=None, **kwargs):
            super().__init__(*args, **kwargs)

    master.Stepper = PythonStepper
    try:
        yield
    finally:
        master.Stepper = original
