"""The trade study's constants against docs/trade.md, the text that states them: timing rounds,
the single run of a slow setting, the front's wall-time tolerance and its default in
``pareto`` (issue 31: constants read back against the text they claim, not against
themselves)."""
from __future__ import annotations

import importlib
import re

from scenarios.studies.trade.measure import pareto
from tests.support.paths import ROOT

DOC = (ROOT / "docs" / "trade.md").read_text()
#: The modules (the package exports functions of the same names).
measure = importlib.import_module("scenarios.studies.trade.measure")
study = importlib.import_module("scenarios.studies.trade.study")


def _number(pattern: str) -> float:
    found = re.search(pattern, DOC)
    assert found, f"docs/trade.md no longer says {pattern!r}"
    return float(found.group(1))


def test_the_timing_rule_is_the_documents():
    """docs/trade.md: "Best of 5 interleaved rounds; a run longer than 5 s runs once."  Catches
    another round count or repeat threshold than the document's."""
    assert study.FULL_ROUNDS == _number(r"Best of (\d+) interleaved rounds")
    assert measure.REPEAT_BELOW_S == _number(r"a run longer than ([0-9.]+) s runs once")
    assert study.QUICK_ROUNDS == 1


def test_the_fronts_tolerance_is_the_documents_and_the_default():
    """docs/trade.md: j dominates i "when j is strictly more accurate and at most 10 % slower".
    Catches another tolerance, a default other than it, and its edge: 9.9 % slower and more
    accurate dominates, 10.1 % does not, and equally accurate never does."""
    tolerance = _number(r"strictly more accurate and at most ([0-9.]+) % slower") / 100
    assert measure.WALL_TOLERANCE == tolerance

    def front(wall_b, err_b):
        rows = [{"setting": "a", "kind": "accuracy", "wall_s": 2.0, "rms_err_m": 1e-4, "error": ""},
                {"setting": "b", "kind": "accuracy", "wall_s": wall_b, "rms_err_m": err_b, "error": ""}]
        return [rows[i]["setting"] for i in pareto(rows)]

    assert front(2.0 * (1 + tolerance) - 2e-3, 5e-5) == ["b"]
    assert front(2.0 * (1 + tolerance) + 2e-3, 5e-5) == ["a", "b"]
    assert front(2.0 * (1 + tolerance) - 2e-3, 1e-4) == ["a"]
    assert front(1.5, 1e-4) == ["b"]


def test_the_full_sweeps_settings_are_the_documents_table_in_its_order():
    """docs/trade.md's first table (the full sweep of bench_circle_TCMDx, every setting applying to
    it) has one row per setting: names, kinds and order as ``settings()`` gives them, and the
    quick sweep's are among them.  Catches a setting added, dropped or changed (another group
    size, sub-step count or table step: seed 4241 [15]) without the document's table."""
    from scenarios.scenes import get_scene
    from scenarios.studies.trade.settings import settings

    table = DOC[DOC.index("| setting | kind | wall [s]"):]
    rows = [line.split(" | ")[:2] for line in table.split("\n\n")[0].splitlines()[2:]]
    documented = [(name.lstrip("| "), kind) for name, kind in rows]
    scene = get_scene("bench_circle_TCMDx")
    assert [(s.name, s.kind) for s in settings()] == documented
    assert all(s.build(scene) is not None for s in settings())
    assert {s.name for s in settings(quick=True)} <= {name for name, _ in documented}
