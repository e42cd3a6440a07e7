"""The mechanical plant: the thesis' modular modelling algorithm (chapters 4-5)
and the 5R parallel robot built with it (chapter 7.1).

The package's names are loaded when first used (PEP 562 ``__getattr__``): importing one
module of it (an FMU's ``plant.fivebar``) imports that module only, not the simulator, the
wheeled pendulum and its drives (``motor``, python-control), so an FMU starts with what its
model needs.
"""
import importlib

#: Name -> the submodule that defines it (a submodule's own name: the submodule).
_EXPORTS = {
    "ChainParams": "presets", "FiveBarParams": "presets", "PRESET_NAMES": "presets", "get_preset": "presets",
    "ACCURATE": "simulator", "ENCODER_COUNTS": "simulator", "IntegratorSettings": "simulator",
    "PlantError": "simulator", "PlantSimulator": "simulator", "wheeled": "wheeled",
}

__all__ = list(_EXPORTS)


def __getattr__(name):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    loaded = importlib.import_module(f"{__name__}.{module}")
    value = loaded if module == name else getattr(loaded, name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_EXPORTS))
