"""benchmarks/side_by_side.py's table from bench_master JSON files (no runs)."""
import json

import pytest

from benchmarks.side_by_side import report


def _write(path, rtfs):
    path.write_text(json.dumps({"runs": {case: [{"rtf": r} for r in values] for case, values in rtfs.items()}}))


def test_ratios_are_this_over_base_per_pair_and_their_median(tmp_path):
    """Catches a ratio taken base over this, a pair's files mixed with another pair's, means instead of
    medians within a run, or a median over the pairs' medians instead of over their ratios."""
    _write(tmp_path / "base_1.json", {"compiled": [100.0, 200.0, 110.0], "fmu": [10.0]})
    _write(tmp_path / "this_1.json", {"compiled": [400.0, 440.0, 1000.0], "fmu": [12.0]})
    _write(tmp_path / "base_2.json", {"compiled": [200.0], "fmu": [5.0]})
    _write(tmp_path / "this_2.json", {"compiled": [500.0], "fmu": [10.0]})
    _write(tmp_path / "base_3.json", {"compiled": [100.0], "fmu": [4.0]})
    _write(tmp_path / "this_3.json", {"compiled": [300.0], "fmu": [3.0]})
    lines = {line.split("|")[1].strip(): line for line in report(tmp_path).splitlines()[2:]}
    assert lines["compiled"].endswith("| 110.0x -> 440.0x (4.00) | 200.0x -> 500.0x (2.50) | 100.0x -> 300.0x (3.00) | 3.00 |")
    assert lines["fmu"].endswith("| 10.0x -> 12.0x (1.20) | 5.0x -> 10.0x (2.00) | 4.0x -> 3.0x (0.75) | 1.20 |")
    assert set(lines) == {"compiled", "fmu"}


def test_a_folder_without_pairs_is_refused_by_name(tmp_path):
    """Catches an empty table printed for a folder that holds no pair (a base file alone is no pair)."""
    _write(tmp_path / "base_1.json", {"compiled": [1.0]})
    with pytest.raises(SystemExit, match=f"no pairs .* in {tmp_path}"):
        report(tmp_path)
