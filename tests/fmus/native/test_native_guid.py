"""A native FMU's GUID (fmus/native/build.py ``package``) is its content's: the same inputs give the
same GUID, and each thing the FMU is made from changes it when it changes alone: the model, a
variable's start, a build scalar, a build array's entry, a source file's byte, a generated
source's text (a native ClosedLoop's loop table: two scenes of one structure differ only there).
A state carries its FMU's GUID, so an FMU whose GUID ignored one of them would take another's
states (docs/native.md: each native FMU has "its own GUID").  The binary is not what is held here:
the compiler is ``true`` (a command that does nothing), so each package takes a fraction of a
second (issue 31: the digest's inputs were never varied one at a time)."""
from __future__ import annotations

import shutil

import pytest
from fmpy import read_model_description

from fmus.native.build import (GENERIC, HERE, NATIVE, SAMPLED, SAMPLED_KERNELS, initialised_slave, kernel_files,
                               package, variables)

MODEL = "Derivator"


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    """(the slave, and the package's inputs as keyword arguments) of the Derivator's native FMU."""
    tmp = tmp_path_factory.mktemp("guid")
    (tmp / "resources").mkdir()
    native = NATIVE[MODEL]
    slave = initialised_slave(MODEL, tmp / "resources")
    scalars, arrays = native.data(slave)
    files = ([HERE / n for n in GENERIC + (SAMPLED if native.sampled else ())]
             + [HERE / "adapters" / n for n in (native.adapter, *native.parts)]
             + kernel_files(native.kernels + (SAMPLED_KERNELS if native.sampled else ())))
    inputs = {"model": MODEL, "rows": variables(slave), "scalars": scalars, "arrays": arrays, "files": files,
              "generated": {"extra_table.h": "/* one */\n"}}
    return tmp, slave, inputs


def _guid(made, name, **changed) -> str:
    tmp, slave, inputs = made
    target = tmp / f"{name}.fmu"
    package(slave=slave, target=target, compiler="true", **{**inputs, **changed})
    return read_model_description(str(target)).guid


def test_the_same_inputs_give_the_same_guid_and_each_input_changes_it(made):
    """Catches a GUID that is not a function of the inputs (a time, a random number), and any one
    of model, rows, scalars, arrays, source files and generated sources left out of its digest
    (or one counted in place of another)."""
    tmp, _, inputs = made
    base = _guid(made, "base")
    assert _guid(made, "again") == base
    rows = [dict(r) for r in inputs["rows"]]
    real = next(r for r in rows if r["type"] == "Real" and r["causality"] == "parameter")
    real["start"] = float(real["start"]) + 1e-9
    scalar = next(iter(inputs["scalars"]))
    array = next(iter(inputs["arrays"]))
    bumped = inputs["arrays"][array].copy()
    bumped.flat[0] += 1.0
    altered = tmp / "altered"
    altered.mkdir()
    first = inputs["files"][0]
    shutil.copy(first, altered / first.name)
    (altered / first.name).write_bytes(first.read_bytes() + b"\n")
    variants = {
        "model": {"model": "Derivator2"},
        "rows": {"rows": rows},
        "scalars": {"scalars": {**inputs["scalars"], scalar: inputs["scalars"][scalar] + 1}},
        "arrays": {"arrays": {**inputs["arrays"], array: bumped}},
        "files": {"files": [altered / first.name, *inputs["files"][1:]]},
        "generated": {"generated": {"extra_table.h": "/* two */\n"}},
    }
    guids = {name: _guid(made, name, **change) for name, change in variants.items()}
    assert all(guid != base for guid in guids.values()), guids
    assert len(set(guids.values())) == len(guids)
