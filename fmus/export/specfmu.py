"""``parcosim build-plant SPEC.toml OUT.fmu``: an FMU of any mechanism spec (:mod:`plant.spec`).

The FMU's slave is :class:`fmus.slaves.parcosim_specplant.SpecPlant`; the spec, checked
here first, travels inside the FMU as the resource ``plant_spec.toml``, so the FMU
needs nothing else than the usual parcosim bundle (:mod:`fmus.export.bundle`).
"""
from __future__ import annotations

import tempfile
from pathlib import Path

from fmus.export.build import ROOT, STATE_OPTIONS, build_bundled_fmu
from fmus.slave.designs import SPEC_RESOURCE

MODEL = "SpecPlant"
SLAVE_MODULE = "parcosim_specplant"


def build_plant_fmu(spec, out) -> Path:
    """Build the FMU of ``spec`` (a path or a shipped spec's name) at ``out``; return its path.

    Raises
    ------
    plant.spec.SpecError
        The spec is not valid (file, line, key, value).
    ValueError
        It describes a serial chain (no ``[platform]``): only parallel mechanisms are plants.
    """
    from plant.spec import load, spec_path

    path = spec_path(spec)
    checked = load(path)
    if not checked.is_parallel:
        raise ValueError(f"{path}: a serial chain (no [platform]) cannot be built as a plant FMU")
    out = Path(out)
    if out.suffix != ".fmu":
        raise ValueError(f"output {str(out)!r} must end in .fmu")
    with tempfile.TemporaryDirectory(prefix="parcosim_specplant_") as tmp:
        spec_file = Path(tmp) / SPEC_RESOURCE
        spec_file.write_text(checked.text, encoding="utf-8")
        return build_bundled_fmu(ROOT / "fmus" / "slaves" / f"{SLAVE_MODULE}.py", MODEL, out, resources=[spec_file],
                                 canHandleVariableCommunicationStepSize="true", **STATE_OPTIONS)
