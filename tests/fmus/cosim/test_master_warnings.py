"""Where the warnings of the public calls point: at the caller's line (``stacklevel``), so that
Python's warning filters and the printed ``file:line`` name the user's script, not parcosim's
insides (issue 31: a warning's ``stacklevel`` off by any amount passed every test)."""
from __future__ import annotations

import warnings
from dataclasses import replace

from fmus.cosim.master import simulate
from fmus.export.build import build_fmu
from scenarios.scenes.catalogue import get_scene


def test_the_compiled_modes_fallback_warning_names_the_callers_line():
    """A plant setting the compiled loop does not step: the fallback's warning is this file's, at
    the line of the ``simulate`` call.  Catches a stacklevel off the caller (parcosim's master or
    the warnings module named instead)."""
    system = get_scene("bench_circle_PDq").system
    components = tuple(replace(c, parameters={**c.parameters, "kernel": "general"}) if c.name == "plant" else c
                       for c in system.components)
    system = replace(system, components=components, stop_time=0.003)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        line = _line() + 1
        result = simulate(system, mode="compiled")
    assert result.mode == "inprocess" and "fallback" in result.extra
    assert [(w.filename, w.lineno) for w in caught] == [(__file__, line)], [(w.filename, w.lineno) for w in caught]


def test_a_foreign_file_left_alone_by_build_fmu_is_warned_at_the_callers_line(tmp_path):
    """``build_fmu`` finds a file it did not build where it would write: the warning names the
    caller.  Catches a stacklevel off the caller."""
    (tmp_path / "Trajectory.fmu").write_bytes(b"not ours")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        line = _line() + 1
        assert build_fmu("Trajectory", tmp_path) is None
    assert [(w.filename, w.lineno) for w in caught] == [(__file__, line)]
    assert "Trajectory.fmu was not built by parcosim: left alone" in str(caught[0].message)


def test_the_skipped_parameters_warning_of_named_models_names_the_callers_line(tmp_path):
    """``named_models`` given a foreign FMU without the component's parameters: the one warning
    listing them is this file's, at the line of the call.  Catches a stacklevel off the caller."""
    import zipfile

    from fmus.cosim.foreign import named_models, replace_components

    # A description only (never run): a CDrive with one parameter, so the others are skipped.
    xml = ('<?xml version="1.0" encoding="UTF-8"?><fmiModelDescription fmiVersion="2.0" modelName="CDrive" '
           'guid="{g}" numberOfEventIndicators="0"><CoSimulation modelIdentifier="CDrive"/><ModelVariables>'
           '<ScalarVariable name="preset" valueReference="0" causality="parameter" variability="fixed">'
           '<Real start="0"/></ScalarVariable></ModelVariables><ModelStructure/></fmiModelDescription>')
    fmu = tmp_path / "a.fmu"
    with zipfile.ZipFile(fmu, "w") as z:
        z.writestr("modelDescription.xml", xml)
    system = replace_components(get_scene("bench_circle_PDq").system, {"drive1": str(fmu)})
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        line = _line() + 1
        named_models(system)
    assert [(w.filename, w.lineno) for w in caught] == [(__file__, line)], [(w.filename, w.lineno) for w in caught]
    assert str(caught[0].message).startswith("parameters the foreign FMUs do not have are skipped: drive1 (a.fmu): ")


def _line() -> int:
    """The caller's line number."""
    import sys

    return sys._getframe(1).f_lineno
