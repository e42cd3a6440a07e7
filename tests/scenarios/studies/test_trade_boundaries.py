"""The trade study's comparisons hit exactly at their edges (issue 31: boundaries never hit):
the Pareto front's dominance (faster and *not less* accurate, or *at most* the tolerance
slower and strictly more accurate, :func:`scenarios.studies.trade.measure.pareto`) and
trade.md's "at least 3× faster" and "at least 100× more accurate" sentences
(:func:`scenarios.studies.trade.report.render`), on made-up rows whose values are exact in
binary floating point."""
from __future__ import annotations

from scenarios.studies.trade import report
from scenarios.studies.trade.measure import Trade, pareto


def _row(name, wall, err, kind="accuracy", error=""):
    return {"setting": name, "kind": kind, "wall_s": wall, "rms_err_m": err, "error": error}


def _front(rows, tol):
    return [rows[i]["setting"] for i in pareto(rows, wall_tolerance=tol)]


def test_a_faster_row_as_accurate_dominates_and_two_equal_rows_both_stay():
    """Faster with the same error dominates (``ej <= ei``); two rows equal in both are on the
    front together (neither is faster, neither more accurate).  Catches ``<=`` for ``<`` on
    either side of the first clause, and the clauses joined by 'or' the wrong way."""
    assert _front([_row("slow", 2.0, 1e-5), _row("fast", 1.0, 1e-5)], 0.0) == ["fast"]
    assert _front([_row("a", 2.0, 1e-5), _row("b", 2.0, 1e-5)], 0.0) == ["a", "b"]
    # Same wall time, strictly more accurate: dominates only through the second clause (wj <= wi).
    assert _front([_row("a", 2.0, 1e-5), _row("b", 2.0, 1e-6)], 0.0) == ["b"]


def test_a_more_accurate_row_exactly_the_tolerance_slower_still_dominates():
    """wi (1 + tol) = 2 × 1.5 = 3.0 exactly: a row 3.0 s against 2.0 s that is more accurate
    takes the faster one's place; at 3.0 + 2⁻⁵⁰ it does not.  Catches ``<=`` turned into ``<``
    at the tolerance and the tolerance added instead of multiplied."""
    assert _front([_row("fast", 2.0, 1e-5), _row("precise", 3.0, 1e-6)], 0.5) == ["precise"]
    assert _front([_row("fast", 2.0, 1e-5), _row("precise", 3.0 + 2.0 ** -50, 1e-6)], 0.5) == ["fast", "precise"]
    # Equally accurate within the tolerance: the slower one is not strictly more accurate, it goes.
    assert _front([_row("same", 3.0, 1e-5), _row("fast", 2.0, 1e-5)], 0.5) == ["fast"]


def test_only_completed_finite_accuracy_rows_take_part():
    """A fidelity row, a stopped run and a NaN deviation neither join the front nor push a row
    off it.  Catches a row filter that lets any of them in."""
    rows = [_row("a", 2.0, 1e-5), _row("fid", 1.0, 1e-9, kind="fidelity"), _row("stop", 1.0, 1e-9, error="x"),
            _row("nan", 1.0, float("nan")), _row("inf", float("inf"), 1e-9)]
    assert _front(rows, 0.1) == ["a"]


def _trade_row(setting, speedup, gain, kind="accuracy"):
    return {"setting": setting, "kind": kind, "what": "w", "wall_s": 2.0 / speedup, "cpu_s": 1.0,
            "speedup": speedup, "rms_err_m": 1e-4 / gain, "max_err_m": 3e-4 / gain, "gain": gain,
            "pareto": False, "error": ""}


def test_exactly_3x_faster_and_exactly_100x_more_accurate_are_listed():
    """Rows at exactly 3.0× the speed and 100.0× the accuracy are named in the sentences that
    say "at least"; rows just under (2.99×, 99.9×) are not.  Catches ``>=`` turned into ``>``
    and the thresholds changed."""
    rows = [_trade_row("defaults", 1.0, 1.0), _trade_row("three", 3.0, 1.0), _trade_row("under3", 2.99, 1.0),
            _trade_row("hundred", 1.0, 100.0), _trade_row("under100", 1.0, 99.9)]
    lines = report.render(Trade("s", 1.0, rows, 1.0), "c").splitlines()
    assert "At least 3× faster: three (3.0×, accuracy, RMS 0.0001 m)." in lines
    faster = next(line for line in lines if line.startswith("At least 3×"))
    assert "under3" not in faster
    accurate = next(line for line in lines if line.startswith("At least 100×"))
    assert accurate == ("At least 100× more accurate: hundred (100×, 1.00× the speed). Most accurate: hundred, "
                        "1e+02× at 1.00× the speed.")


def test_a_fidelity_row_is_never_the_accurate_one_and_a_stopped_row_never_the_fast_one():
    """A fidelity switch with a 1000× gain is not 'more accurate' (its deviation is a change of
    the model); a stopped run with a 10× speed-up is not 'faster'.  Catches the kind or the
    error filter dropped from either sentence."""
    rows = [_trade_row("defaults", 1.0, 1.0), _trade_row("fid", 1.0, 1000.0, kind="fidelity"),
            {**_trade_row("stopped", 10.0, 1.0), "error": "plant: refused at t = 0.2 s"}]
    lines = report.render(Trade("s", 1.0, rows, 1.0), "c").splitlines()
    assert "At least 3× faster: none." in lines
    assert "At least 100× more accurate: none. Most accurate: defaults, 1× at 1.00× the speed." in lines
