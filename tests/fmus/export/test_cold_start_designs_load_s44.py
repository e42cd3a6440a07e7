"""``fmus.slave.designs.load``'s count and its once-per-folder rule (fmus/slave/designs.py:
"return how many"; "No file ... loads none"; "once per folder and process"), on a designs file
written here with :func:`fmus.slave.designs.write` (no FMU built, no design computed)."""
from __future__ import annotations

import numpy as np

from fmus.slave import designs

#: A derivator's filter as the file keeps it (any array: load puts back what write wrote).
SOS = np.arange(12.0).reshape(2, 6) / 7.0
#: A key no real design has (the derivators' keys are tuples too: read back as tuples).
KEY = ("test_designs_load_s44", 2, 1e-3, ("nested", 1))


def test_load_counts_what_it_puts_back_and_nothing_without_a_file_or_a_second_time(tmp_path):
    """No folder (in process: None, ""), a folder without the file: 0, nothing put back. The
    file's one design: 1, put back exactly (its tuple key too); the same folder again: 0 and
    not put back again. Catches a count made up for no file or a folder already loaded, and a
    folder loaded twice."""
    designs.write({"controller.derivators": {KEY: SOS}}, tmp_path / designs.DESIGNS_FILE)
    empty = tmp_path / "empty"
    empty.mkdir()
    with designs.isolated() as modules:
        store = modules["controller.derivators"].PRECOMPUTED
        store.pop(KEY, None)
        assert designs.load(None) == 0 and designs.load("") == 0
        assert designs.load(str(empty)) == 0
        assert KEY not in store
        assert designs.load(str(tmp_path)) == 1
        np.testing.assert_array_equal(store[KEY], SOS)
        del store[KEY]
        assert designs.load(str(tmp_path)) == 0
        assert KEY not in store
