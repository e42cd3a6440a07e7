"""The mechanical plant: the thesis' modular modelling algorithm (chapters 4-5)
and the 5R parallel robot built with it (chapter 7.1)."""
from .presets import ChainParams, FiveBarParams, PRESET_NAMES, get_preset
from .simulator import ACCURATE, ENCODER_COUNTS, IntegratorSettings, PlantError, PlantSimulator
# Imported with the package: a slave built after another (pythonfmu imports each from its own
# temporary copy of the package, deleted after the build) finds it already loaded.
from . import wheeled  # noqa: E402,F401

__all__ = [
    "ChainParams", "FiveBarParams", "PRESET_NAMES", "get_preset",
    "ACCURATE", "ENCODER_COUNTS", "IntegratorSettings", "PlantError", "PlantSimulator", "wheeled",
]
