"""scenarios/studies/tools.py's command line and its docs writer, without a tool run: each
option taking effect (``--tools``, ``--kinds`` and its refusal, ``--results``, ``--out``,
``--docs`` running nothing and writing the tables between the markers of docs/ssp.md and the
README, here copies), the default scenes, and the text outside the markers kept byte for
byte (issue 31: CLI options actually taking effect; every written value read back)."""
from __future__ import annotations

import json

import pytest

import scenarios.studies.tools as tools

OURS = {"e_ef_mm": 0.5, "tau_ef_Nm": 0.02}
RUN = {"e_ef_mm": 0.55, "tau_ef_Nm": 0.021, "completed": True, "cpu_s": 0.3, "simulated_s": 0.2, "step": 1e-3}


def _doc(path, body="old table\n"):
    path.write_text(f"# title\n\nbefore\n{tools.TABLE_START}{body}{tools.TABLE_END}\nafter ü\n")
    return path


def test_write_docs_table_replaces_only_what_lies_between_the_markers(tmp_path):
    """Catches the table written outside the markers, a marker lost, the old table kept, and
    the text before or after changed."""
    path = _doc(tmp_path / "ssp.md")
    tools.write_docs_table("| a | b |\n", path)
    assert path.read_text() == f"# title\n\nbefore\n{tools.TABLE_START}\n| a | b |\n{tools.TABLE_END}\nafter ü\n"
    tools.write_docs_table("second\n", path)
    assert path.read_text() == f"# title\n\nbefore\n{tools.TABLE_START}\nsecond\n{tools.TABLE_END}\nafter ü\n"


@pytest.fixture
def measured(monkeypatch):
    asked = []

    def measure(scenes, tool_names, kinds, results, progress):
        asked.append((list(scenes), list(tool_names), list(kinds), results))
        return {(kinds[0], scenes[0]): [(t, RUN, OURS, None) for t in tool_names]}

    monkeypatch.setattr(tools, "measure", measure)
    return asked


def test_the_options_choose_the_scenes_tools_kinds_results_and_output(measured, tmp_path, capsys):
    """Catches ``--tools`` or ``--kinds`` not split or ignored, the default scenes not the
    table's, ``--results`` not the file measured into, and ``--out`` not the printed text."""
    out = tmp_path / "tables.md"
    assert tools.main(["bench_circle_PDq", "--tools", "ecos,fmpy", "--kinds", "per-component,default",
                       "--results", str(tmp_path / "r.json"), "--out", str(out)]) == 0
    assert measured == [(["bench_circle_PDq"], ["ecos", "fmpy"], ["per-component", "default"],
                         str(tmp_path / "r.json"))]
    results = {("per-component", "bench_circle_PDq"): [(t, RUN, OURS, None) for t in ("ecos", "fmpy")]}
    text = tools.summary(results) + "\n" + tools.table(results)
    assert capsys.readouterr().out == text + "\n" and out.read_text() == text
    measured.clear()
    assert tools.main([]) == 0
    assert measured == [(list(tools.TABLE_SCENES), list(tools.TOOLS), list(tools.KINDS), str(tools.RESULTS))]


def test_an_unknown_kind_is_refused_naming_it_and_the_valid_ones(measured, capsys):
    """Catches a misspelt kind run (or skipped) instead of refused."""
    with pytest.raises(SystemExit) as stop:
        tools.main(["--kinds", "default,per-componet"])
    assert stop.value.code == 2 and measured == []
    assert f"--kinds per-componet: one of {', '.join(tools.KINDS)}" in capsys.readouterr().err


def test_docs_runs_nothing_and_writes_the_stored_tables_into_the_docs_and_the_summary_into_the_readme(
        measured, monkeypatch, tmp_path, capsys):
    """Catches ``--docs`` running the tools, the tables not of the stored runs (or of other
    tools), the README given the whole table or docs/ssp.md only the summary."""
    results = tmp_path / "tools.json"
    stored = {"ours|bench_circle_PDq|parcosim": OURS,
              **{f"default|bench_circle_PDq|{t}": {"metrics": RUN, "error": None} for t in tools.TOOLS}}
    results.write_text(json.dumps(stored))
    monkeypatch.setattr(tools, "DOCS", _doc(tmp_path / "ssp.md"))
    monkeypatch.setattr(tools.write_docs_table, "__defaults__", (tools.DOCS,))   # bound at definition
    monkeypatch.setattr(tools, "README", _doc(tmp_path / "README.md", "old summary\n"))
    assert tools.main(["--docs", "--results", str(results), "--tools", "fmpy"]) == 0
    assert measured == []
    rows = tools.stored_rows(tools.load_results(results), ["fmpy"])
    assert [r[0] for r in rows[("default", "bench_circle_PDq")]] == ["fmpy"]
    text = tools.summary(rows) + "\n" + tools.table(rows)
    assert capsys.readouterr().out == text + "\n"
    assert (tmp_path / "ssp.md").read_text() == \
        f"# title\n\nbefore\n{tools.TABLE_START}\n{text}{tools.TABLE_END}\nafter ü\n"
    assert (tmp_path / "README.md").read_text() == \
        f"# title\n\nbefore\n{tools.TABLE_START}\n{tools.summary(rows)}{tools.TABLE_END}\nafter ü\n"


def test_the_help_says_how_to_give_the_tools_and_kinds_and_lists_the_valid_ones(measured, capsys, monkeypatch):
    """``--help`` (the command's only reference for the lists' syntax): ``--tools`` and ``--kinds``
    are comma-separated, each from every valid value; it runs nothing.  Catches the syntax or a
    list of valid values left out of an option's help."""
    monkeypatch.setenv("COLUMNS", "400")     # no wrapping (argparse breaks lines at hyphens)
    with pytest.raises(SystemExit) as stop:
        tools.main(["--help"])
    assert stop.value.code == 0 and measured == []
    text = " ".join(capsys.readouterr().out.split())
    for option, valid in (("--tools", tools.TOOLS), ("--kinds", tools.KINDS)):
        assert f"{option} {option[2:].upper()} comma-separated, from {', '.join(valid)}" in text, option
