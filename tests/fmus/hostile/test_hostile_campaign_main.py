"""fmus/hostile/campaign.py's command with the FMUs and their runs replaced (the campaign itself is
of the slow kind): the cases spread over the FMUs from the first seed, the kinds an FMU without
parcosim's wrapper cannot honour left out, every result written to cases.jsonl and read back,
summary.md's text and the exit status (issue 31: "fmus other"; every written value read back)."""
from __future__ import annotations

import json

import pytest

from fmus.hostile import campaign
from fmus.hostile import cases as hostile
from fmus.hostile.cases import CaseResult


@pytest.fixture
def made_up(monkeypatch, tmp_path):
    """Two FMUs (one with our wrapper), cases recorded, results given by the test."""
    asked, state = [], {"outcomes": {}}
    monkeypatch.setattr(campaign.tempfile, "mkdtemp", lambda prefix: str(tmp_path / "work"))   # nothing left in /tmp
    monkeypatch.setattr(hostile, "prepared_fmus", lambda fmu_dir, models, work: {"Plant": "/u/plant", "Drive": "/u/drive"})
    monkeypatch.setattr(hostile, "wrapper_is_ours", lambda path, model: model == "Plant")

    def cases_for(model, path, seeds, wrapper, kinds):
        asked.append((model, path, list(seeds), wrapper, tuple(kinds)))
        return [{"model": model, "kind": kinds[k % len(kinds)], "seed": s} for k, s in enumerate(seeds)]

    def run_cases(cases, unzipped, batch, progress, env):
        state["batch"], state["env"] = batch, env
        results = [CaseResult(c, state["outcomes"].get((c["model"], c["seed"]), "ok"), [["doStep", "OK"]],
                              [], 0.25 * k) for k, c in enumerate(cases)]
        for r in results:
            progress(r)
        return results

    monkeypatch.setattr(hostile, "cases_for", cases_for)
    monkeypatch.setattr(hostile, "run_cases", run_cases)
    return asked, state


def test_the_cases_spread_over_the_fmus_and_every_result_is_written(made_up, tmp_path, capsys):
    """5 cases over 2 FMUs: 3 each from seed 10; the FMU without our wrapper gets no wrapper
    kind.  Catches the share rounded down, seeds not from --seed, the kinds not filtered (or
    filtered for our wrapper), a result missing from cases.jsonl or changed, the batch size not
    passed, and an exit status of 1 when every case was ok or refused."""
    asked, state = made_up
    state["outcomes"] = {("Drive", 11): "refused"}
    out = tmp_path / "out"
    assert campaign.main(["--cases", "5", "--seed", "10", "--out", str(out), "--batch", "7"]) == 0
    plain = tuple(k for k in hostile.KINDS if k not in hostile.WRAPPER_KINDS)
    assert asked == [("Plant", "/u/plant", [10, 11, 12], True, hostile.KINDS),
                     ("Drive", "/u/drive", [10, 11, 12], False, plain)]
    assert state["batch"] == 7 and state["env"] is None
    lines = [json.loads(line) for line in (out / "cases.jsonl").read_text().splitlines()]
    assert [(r["case"]["model"], r["case"]["seed"], r["outcome"]) for r in lines] == \
        [("Plant", 10, "ok"), ("Plant", 11, "ok"), ("Plant", 12, "ok"), ("Drive", 10, "ok"), ("Drive", 11, "refused"),
         ("Drive", 12, "ok")]
    assert [r["seconds"] for r in lines] == [0.25 * k for k in range(6)]
    assert all(r["statuses"] == [["doStep", "OK"]] and r["problems"] == [] for r in lines)
    text = (out / "summary.md").read_text()
    first, rest = text.split("\n\n", 1)
    assert first.startswith("6 cases, ") and first.endswith(
        "s wall (parcosim's FMI wrapper, pythonfmu 0.7's binary); `python -m fmus.hostile.campaign --cases 5 --seed 10`")
    results = [CaseResult(r["case"], r["outcome"], r["statuses"], r["problems"], r["seconds"]) for r in lines]
    assert rest == hostile.markdown_summary(results) + "\n"
    assert capsys.readouterr().out == text + "\n"


def test_a_case_that_broke_a_property_makes_the_exit_status_1_and_is_reported(made_up, tmp_path, capsys):
    """Catches a violation, crash or hang not failing the campaign, and the progress line of a
    bad case not naming its model, kind and seed."""
    _, state = made_up
    for bad in ("violation", "crash", "hang", "fatal"):
        state["outcomes"] = {("Plant", 0): bad}
        assert campaign.main(["--cases", "2", "--seed", "0", "--out", str(tmp_path / bad)]) == 1, bad
        err = capsys.readouterr().err
        assert f"{bad}: Plant " in err and " seed 0 " in err, bad


def test_loop_without_native_is_a_usage_error(made_up, tmp_path):
    """Catches --loop accepted without --native (it names a native ClosedLoop FMU)."""
    with pytest.raises(SystemExit) as info:
        campaign.main(["--loop", "x.fmu", "--out", str(tmp_path)])
    assert info.value.code == 2


def test_native_passes_its_options_on_and_says_how_the_fmus_were_built(made_up, tmp_path, monkeypatch, capsys):
    """``--native``: the FMU folder, the models, the work folder, the sanitizers (unless
    ``--no-sanitize``) and the loop reach ``prepared_native_fmus``; the sanitizers' reports
    go to OUT/sanitizer; every FMU is driven as native (every kind); the summary names the
    binaries and the command with ``--native`` and ``--loop``.  Catches an option dropped
    or swapped, the sanitizers' environment not passed to the runs, and the wording of the
    binaries or of the command wrong."""
    asked, state = made_up
    prepared, environments = [], []

    def prepared_native_fmus(fmu_dir, models, work, sanitize, loop_fmu):
        prepared.append((fmu_dir, models, work, sanitize, loop_fmu))
        return {"ClosedLoop": "/u/loop", "Drive": "/u/drive"}

    def sanitizer_env(folder):
        environments.append(folder)
        return {"ASAN_OPTIONS": "x"}

    monkeypatch.setattr(hostile, "prepared_native_fmus", prepared_native_fmus)
    monkeypatch.setattr(hostile, "sanitizer_env", sanitizer_env)
    monkeypatch.setattr(hostile, "is_native", lambda path: True)
    out = tmp_path / "out"
    assert campaign.main(["--native", "--cases", "2", "--fmu-dir", "fd", "--models", "ClosedLoop,Drive",
                          "--loop", "l.fmu", "--out", str(out)]) == 0
    assert prepared == [("fd", "ClosedLoop,Drive", tmp_path / "work", True, "l.fmu")]
    assert environments == [out / "sanitizer"] and state["env"] == {"ASAN_OPTIONS": "x"} and state["batch"] == 30
    assert [a[3:] for a in asked] == [(True, hostile.KINDS)] * 2
    first = (out / "summary.md").read_text().split("\n\n", 1)[0]
    assert first.endswith("s wall (native FMUs, rebuilt with -fsanitize=address,undefined); "
                          "`python -m fmus.hostile.campaign --native --loop l.fmu --cases 2 --seed 0`")
    assert campaign.main(["--native", "--no-sanitize", "--cases", "2", "--out", str(out)]) == 0
    assert prepared[1] == (None, None, tmp_path / "work", False, None)
    assert len(environments) == 1 and state["env"] is None
    first = (out / "summary.md").read_text().split("\n\n", 1)[0]
    assert first.endswith("s wall (native FMUs); `python -m fmus.hostile.campaign --native --cases 2 --seed 0`")


def test_the_defaults_are_3000_cases_from_seed_0_in_batches_of_30_into_out_hostile(made_up, tmp_path, monkeypatch):
    """Catches a default changed or an option's default not taking effect."""
    asked, state = made_up
    monkeypatch.chdir(tmp_path)
    assert campaign.main([]) == 0
    assert [(a[0], a[2][0], len(a[2])) for a in asked] == [("Plant", 0, 1500), ("Drive", 0, 1500)]
    assert state["batch"] == 30
    assert "--cases 3000 --seed 0`" in (tmp_path / "out" / "hostile" / "summary.md").read_text().split("\n")[0]


def test_help_says_what_the_campaign_is(capsys):
    """Catches the description (the module docstring's first line) left out of ``--help``."""
    with pytest.raises(SystemExit) as info:
        campaign.main(["--help"])
    assert info.value.code == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "The long hostile-use campaign (issue 13): thousands of cases through fmpy, a summary table." in text


def test_the_wall_time_and_the_progress_lines_count_from_the_cases_start(made_up, tmp_path, monkeypatch, capsys):
    """A clock that reads 1000 s when the cases start and advances 0.5 s a case: the progress
    lines (every 100 cases) say 50 and 100 s, the summary "200 cases, 100 s wall".  Catches the
    elapsed time taken from another start (the clock's reading itself, or the first case's)."""
    _, state = made_up
    now = [1000.0]
    monkeypatch.setattr(campaign, "time", type("Clock", (), {"perf_counter": staticmethod(lambda: now[0])}))

    def run_cases(cases, unzipped, batch, progress, env):
        results = []
        for c in cases:
            now[0] += 0.5
            results.append(CaseResult(c, "ok", [], [], 0.5))
            progress(results[-1])
        return results

    monkeypatch.setattr(hostile, "run_cases", run_cases)
    out = tmp_path / "out"
    assert campaign.main(["--cases", "200", "--out", str(out)]) == 0
    assert capsys.readouterr().err.splitlines() == ["100/200 50 s", "200/200 100 s"]
    assert (out / "summary.md").read_text().startswith("200 cases, 100 s wall (")
