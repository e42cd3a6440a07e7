"""The mechanical plant: the thesis' modular modelling algorithm (chapters 4-5)
and the 5R parallel robot built with it (chapter 7.1)."""
from .presets import ChainParams, FiveBarParams, PRESET_NAMES, get_preset
from .simulator import ACCURATE, IntegratorSettings, PlantError, PlantSimulator

__all__ = [
    "ChainParams", "FiveBarParams", "PRESET_NAMES", "get_preset",
    "ACCURATE", "IntegratorSettings", "PlantError", "PlantSimulator",
]
