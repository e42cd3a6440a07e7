"""``parcosim build-plant SPEC.toml OUT.fmu``: an FMU of any mechanism spec (:mod:`plant.spec`).

The FMU's slave is :class:`fmus.slaves.parcosim_specplant.SpecPlant`; the spec, checked
here first, travels inside the FMU as the resource ``plant_spec.toml``, so the FMU
needs nothing else than the usual parcosim bundle (:func:`fmus.build.stage_sources`).
"""
from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

from pythonfmu import FmuBuilder

from .build import ROOT, STATE_OPTIONS, stage_sources
from .foreign import mark_file
from .modeldescription import fix_model_structure
from .wrapper import install_wrapper

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
    out.parent.mkdir(parents=True, exist_ok=True)
    from .slaves.parcosim_specplant import SPEC_RESOURCE

    with tempfile.TemporaryDirectory(prefix="parcosim_specplant_") as tmp:
        tmp = Path(tmp)
        (tmp / SPEC_RESOURCE).write_text(checked.text, encoding="utf-8")
        project_files = stage_sources(tmp) + [mark_file(tmp, MODEL), tmp / SPEC_RESOURCE]
        script = tmp / f"{SLAVE_MODULE}.py"
        shutil.copy2(ROOT / "fmus" / "slaves" / script.name, script)
        fmu = FmuBuilder.build_FMU(script, dest=tmp / "out" / f"{MODEL}.fmu", project_files=project_files,
                                   canHandleVariableCommunicationStepSize="true", **STATE_OPTIONS)
        fix_model_structure(fmu, {})
        install_wrapper(fmu)
        shutil.move(fmu, out)
    return out
