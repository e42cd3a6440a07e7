"""The identity a parcosim FMU carries in its resources (``parcosim_build.json``).

One small JSON object, written at build time:

* ``model``, ``built_by``: which parcosim model it is (:mod:`fmus.cosim.foreign`'s mark, so that
  the build never overwrites an FMU it did not make);
* ``package``: the private package the bundled model code runs under
  (``parcosim_<hash>``, :mod:`fmus.export.bundle`);
* ``guid``, ``model_identifier``: the GUID and the co-simulation modelIdentifier of the
  FMU's modelDescription.xml, written by :func:`fmus.export.wrapper.install_wrapper` last in the
  build.  parcosim's FMI wrapper refuses an instantiation whose GUID or binary is not
  these (resources of another FMU), and the slave knows its FMU's GUID from it
  (:attr:`fmus.slave.base.GuardedSlave.fmu_guid`).

Bundled into every FMU (the slave reads it); imports nothing of parcosim.
"""
from __future__ import annotations

import json
import os

#: The identity's file name in an FMU's resources.
IDENTITY_FILE = "parcosim_build.json"


def read_identity(resources) -> dict:
    """The identity in the folder ``resources``; {} when there is none (in process, or an
    FMU parcosim did not build) or it is not a JSON object."""
    if not resources:
        return {}
    try:
        with open(os.path.join(resources, IDENTITY_FILE), encoding="utf-8") as f:
            identity = json.load(f)
    except (OSError, ValueError):
        return {}
    return identity if isinstance(identity, dict) else {}
