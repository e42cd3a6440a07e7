"""Run a system with the native FMUs: ``parcosim run SCENE --mode fmu --native``.

:func:`native_system` gives each component whose model has a native FMU
(:data:`fmus.native.models.NATIVE`) a native FMU file built with the component's parameters as
its start values (so the designs it carries are that component's), cached in a folder by
a digest of the model, the parameters and the sources; the other components stay the
pythonfmu FMUs of ``--mode fmu``.
"""
from __future__ import annotations

import hashlib
import json
from dataclasses import replace
from pathlib import Path

from .build import DEFAULT_NATIVE_OUT, build_native_fmu, source_digest
from .models import NATIVE


def native_fmu_for(model: str, parameters: dict, out_dir=DEFAULT_NATIVE_OUT, digest: str | None = None) -> Path:
    """The native FMU of ``model`` with ``parameters`` as start values, built unless the
    folder holds it already (same model, parameters and sources)."""
    key = json.dumps([model, sorted(parameters.items()), digest or source_digest()], default=repr)
    name = f"{model}-{hashlib.sha256(key.encode()).hexdigest()[:16]}"
    path = Path(out_dir) / f"{name}.fmu"
    if path.exists():
        return path
    return build_native_fmu(model, out_dir, start_values=dict(parameters), file_name=name)


def refuse_without_native(system, what: str) -> None:
    """Refuse, in one line that names them, ``system``'s components whose model has no
    native FMU (SpecPlant); components given as FMU files go as they are.

    Raises
    ------
    ValueError
        ``what`` (e.g. "scene bench_x: export-ssp --native") and each such component with its model.
    """
    from fmus.cosim.foreign import is_fmu_file

    missing = [f"{c.name} ({c.model})" for c in system.components if c.model not in NATIVE and not is_fmu_file(c.model)]
    if missing:
        raise ValueError(f"{what}: no native FMU of {', '.join(missing)} (native: {', '.join(NATIVE)}); "
                         "export it without --native")


def native_instances(system, out_dir=DEFAULT_NATIVE_OUT) -> dict:
    """Instance -> the native FMU file built with that instance's parameters as its start
    values (:func:`native_fmu_for`), for every component of a natively built model."""
    digest = source_digest()
    return {c.name: native_fmu_for(c.model, c.parameters, out_dir, digest) for c in system.components
            if c.model in NATIVE}


def native_system(system, out_dir=DEFAULT_NATIVE_OUT):
    """``system`` with every component of a natively built model run as its native FMU file."""
    built = native_instances(system, out_dir)
    components = tuple(replace(c, model=str(built[c.name].resolve())) if c.name in built else c
                       for c in system.components)
    return replace(system, components=components)


def with_native_fmus(scene, out_dir=DEFAULT_NATIVE_OUT):
    """``scene`` whose system runs its natively built models as native FMUs (:func:`native_system`)."""
    native = [c.name for c in scene.system.components if c.model in NATIVE]
    return replace(scene, system=native_system(scene.system, out_dir),
                   description=f"{scene.description}; native FMUs: {', '.join(native) or 'none'}")
