"""What the tests that run packages in other tools share: which tools load here, and the
short bench scene they run."""
from __future__ import annotations

import dataclasses

from fmus.ssp.run import ecos_available
from scenarios.scenes.catalogue import get_scene


def _libcosim_reason():
    from fmus.ssp.libcosim import libcosim_available

    return libcosim_available()


#: Tool -> None when it loads here, else the reason it cannot (the tests skip with it).
UNAVAILABLE = {"fmpy": None, "ecos": ecos_available(), "libcosim": _libcosim_reason()}


def short_bench(stop: float, window: tuple):
    """``bench_circle_TCMDx`` cut at ``stop`` with its metrics over ``window``."""
    s = get_scene("bench_circle_TCMDx")
    return dataclasses.replace(s, system=dataclasses.replace(s.system, stop_time=stop), window=window)
