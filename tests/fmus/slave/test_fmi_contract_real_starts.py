"""Every Real start value in a parcosim model's modelDescription.xml (``to_xml``, fmus/slave/base.py)
reads back as the declared start exactly, last bit included (pythonfmu's own 16 significant
digits give back about three doubles in four: WheeledPendulum's J_psi)."""
from __future__ import annotations

import importlib

import pytest

from fmus.slave.registry import SLAVES


@pytest.mark.parametrize("model", sorted(SLAVES))
def test_every_real_start_in_the_model_description_is_the_declared_start_to_the_last_bit(model):
    slave = getattr(importlib.import_module(f"fmus.slaves.{SLAVES[model]}"), model)(instance_name="m")
    declared = {v.name: getattr(slave, v.name) for v in slave.vars.values()}
    read = {}
    for sv in slave.to_xml().find("ModelVariables"):
        real = sv.find("Real")
        if real is not None and real.get("start") is not None:
            read[sv.get("name")] = float(real.get("start"))
    assert read and all(read[name] == declared[name] for name in read), \
        {n: (read[n], declared[n]) for n in read if read[n] != declared[n]}
