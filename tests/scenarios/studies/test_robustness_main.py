"""``python -m scenarios.studies.robustness --render-only``: the tables and the figure from the
sweeps already written (scenarios/studies/robustness.py ``main``), nothing run."""
from __future__ import annotations

import sys

from scenarios.batch import sweep
from scenarios.scenes import get_scene
from scenarios.scenes.perturb import perturbable
from scenarios.studies import robustness


def _write_sweep(out, scene, folder, e_ef):
    header = sweep.columns([p.name for p in perturbable(get_scene(scene))])
    path = out / scene / folder / "sweep.csv"
    path.parent.mkdir(parents=True)
    appender = sweep._Appender(path, header)
    for k, e in enumerate(e_ef):
        appender.append({**{name: 0.5 for name in header}, "sample": k, "completed": True,
                         **sweep.error_columns({"outcome": "completed"}), "e_ef_mm": e, "tau_ef_Nm": 0.02,
                         "e_ss_mm": 0.01, "e_ss_1s_mm": 0.0, "t_settle_s": 1.0, "wall_s": 1.0})
    appender.close()


def test_render_only_writes_the_tables_with_the_command_line_and_the_figure(tmp_path, monkeypatch, capsys):
    """Called as a program (argv from sys.argv): robustness.md quotes the command with every
    argument given, robustness.png is a PNG beside it, and the md's path is printed.  Catches the
    command's first argument dropped and the figure written over the folder's name."""
    _write_sweep(tmp_path, "bench_circle_PDq", "U0", [0.4])
    _write_sweep(tmp_path, "bench_circle_PDq", "U0.2", [0.5, 0.7, 0.6])
    _write_sweep(tmp_path, "bench_circle_PDMDq", "U0.2", [0.3, 0.35, 0.45])
    args = ["--render-only", "--out", str(tmp_path), "--uncertainties", "0.2"]
    monkeypatch.setattr(sys, "argv", ["robustness.py", *args])
    assert robustness.main() == 0
    text = (tmp_path / "robustness.md").read_text()
    assert f"`python -m scenarios.studies.robustness {' '.join(args)}`" in text.splitlines()
    assert "| PDq | 0.400 | 0.600 |" in text
    assert (tmp_path / "robustness.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert capsys.readouterr().out.strip() == str(tmp_path / "robustness.md")
    given = ["--out", str(tmp_path), "--render-only"]
    assert robustness.main(given) == 0      # argv given: quoted as given
    assert f"`python -m scenarios.studies.robustness {' '.join(given)}`" in (tmp_path / "robustness.md").read_text()
