"""The in-process master with every slave through its Python ``do_step`` (its stepper without
the kernel segments of :mod:`fmus.cosim.segments`): the independent path that the segments'
rows, records and states are compared with.  The benchmark's own context manager, so the
benchmark's "Python slaves" case and the tests' reference are the same thing."""
from benchmarks.bench_master import python_slaves

__all__ = ["python_slaves"]
