"""Start-up of a sweep's worker process (a dask preload module): drop from ``sys.path`` the
``resources`` folders of FMUs extracted in the parent process.

A worker process is spawned with its parent's ``sys.path``.  A parent that has run a
pythonfmu FMU in process (``mode="fmu"``, fmpy) has that FMU's ``resources`` folder on its
path, with a copy of ``fmus``, ``plant``, ``motor`` and ``controller`` that may be older than
the installed ones; a worker importing those would run another code.  This module imports
nothing of parcosim, so it runs before any of it is imported; the engine gives it to dask by
file (importing it by name would import the ``scenarios`` package first).
"""
from __future__ import annotations

import sys
from pathlib import Path


def is_fmu_resources(entry: str) -> bool:
    """``entry`` is the resources folder of an extracted FMU (beside its modelDescription.xml)."""
    path = Path(entry)
    return path.name == "resources" and (path.parent / "modelDescription.xml").is_file()


def dask_setup(worker=None) -> None:
    """The preload hook: remove the extracted FMUs' resources folders from ``sys.path``."""
    sys.path[:] = [entry for entry in sys.path if not is_fmu_resources(entry)]
