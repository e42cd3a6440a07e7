"""scenarios/studies/trade/study.run_trade's files, with the runs replaced by made-up rows (the
real sweep takes minutes): a full run writes trade.csv, noquant.csv (the sweep without encoder
quantisation), trade.png and trade.md, in that order, each CSV holding its own rows; a quick run
writes no noquant.csv (seed 4101 [160]: no test ran the full run with a folder)."""
from __future__ import annotations

import csv
from types import SimpleNamespace

import pytest

from scenarios.studies.trade import study


def _rows(prefix):
    return [{"setting": f"{prefix}{k}", "kind": "coupling", "what": f"row {k}", "wall_s": 0.5 + k} for k in range(2)]


@pytest.fixture
def made_up(monkeypatch):
    monkeypatch.setattr(study, "reference_run", lambda scene: SimpleNamespace(completed=True, wall_s=2.0, error=None))
    monkeypatch.setattr(study, "_sweep", lambda base, chosen, reference, rounds, say: (_rows("sweep"), []))
    monkeypatch.setattr(study, "_relative", lambda rows: None)
    monkeypatch.setattr(study, "_noquant", lambda base, rounds, say: _rows("noquant"))
    monkeypatch.setattr(study, "plot", lambda trade, path: path.write_bytes(b"png") and path)
    monkeypatch.setattr(study, "render", lambda trade, command: f"{command}\n")


def _read(path):
    with open(path, newline="") as stream:
        return [row["setting"] for row in csv.DictReader(stream)]


@pytest.mark.parametrize("quick", [False, True])
def test_a_run_with_a_folder_writes_its_files_in_order_the_full_one_with_its_unquantised_sweep(tmp_path, made_up,
                                                                                              quick):
    """Catches noquant.csv left unwritten or unlisted in a full run, written in a quick one, written with the
    sweep's rows, or the files listed in another order; the folder made without its missing parent
    (sibling of seed 4201 [196])."""
    tmp_path = tmp_path / "new" / "out"
    trade = study.run_trade("bench_circle_TCMDx", quick=quick, out_dir=tmp_path, stop_time=0.01, rounds=1)
    names = ["trade.csv"] + ([] if quick else ["noquant.csv"]) + ["trade.png", "trade.md"]
    assert trade.files == [tmp_path / name for name in names]
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(names)
    assert _read(tmp_path / "trade.csv") == ["sweep0", "sweep1"]
    if not quick:
        assert _read(tmp_path / "noquant.csv") == ["noquant0", "noquant1"] and trade.noquant == _rows("noquant")
    command = f"parcosim trade bench_circle_TCMDx{' --quick' if quick else ''} --out {tmp_path}"
    assert (tmp_path / "trade.md").read_text() == command + "\n"
