"""scenarios/batch/sweep.py's files and statistics without running a sweep (its tests that run
scenes on dask are of the slow kind): a torn last row, another sweep's header, the statistics
against numpy's definitions written here, summary.md's table read back, a scene cut short
(issue 31: every serialised value read back exactly)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from scenarios.batch import sweep
from scenarios.scenes import get_scene

HEADER = sweep.columns(["drive1.R", "plant.l0"])


def _row(sample, value, completed=True, error=""):
    """A row; a failed one carries a refusal record's fields (a completed one has none: NaN,
    None or "")."""
    record = {"outcome": "refused", "error_instance": "plant", "error_time": 0.25 + value,
              "error_variable": "q1", "error_value": -1.5e300, "error_unit": "rad", "error_code": 3,
              "error_reason": "absurd"} if error else {
              "outcome": "completed", "error_instance": "", "error_time": math.nan, "error_variable": "",
              "error_value": math.nan, "error_unit": "", "error_code": None, "error_reason": ""}
    return {"sample": sample, "drive1.R": 1.1 + value, "plant.l0": 0.05 - value / 1e3, "e_ef_mm": 0.5 + value,
            "tau_ef_Nm": 0.02 * (1 + value), "e_ss_mm": math.nan if sample == 2 else 0.1 * value,
            "e_ss_1s_mm": 0.3, "t_settle_s": 1.0 + value, "completed": completed, **record, "error": error,
            "wall_s": 3.0 + sample}


def _same(a, b) -> bool:
    """Rows equal value for value, NaN equal to NaN (a completed row's error time and value)."""
    return len(a) == len(b) and all(
        x.keys() == y.keys() and all(x[k] == y[k] or (isinstance(x[k], float) and math.isnan(x[k])
                                                     and isinstance(y[k], float) and math.isnan(y[k])) for k in x)
        for x, y in zip(a, b))


def _write(path, rows):
    appender = sweep._Appender(path, HEADER)
    for row in rows:
        appender.append(row)
    appender.close()


def test_the_header_is_sample_parameters_metrics_then_the_tail():
    assert HEADER == ["sample", "drive1.R", "plant.l0", "e_ef_mm", "tau_ef_Nm", "e_ss_mm", "e_ss_1s_mm",
                      "t_settle_s", "completed", "outcome", "error_instance", "error_time", "error_variable",
                      "error_value", "error_unit", "error_code", "error_reason", "error", "wall_s"]


def test_a_torn_last_row_is_left_out_and_cut_off_only_when_repairing(tmp_path):
    """A row killed mid-write: a reader skips it and leaves the file as it is; the sweep that
    continues the file cuts it off, after which an appended row reads back whole.  Catches
    the cut made by a plain reader, the torn row parsed, the cut one byte off."""
    path = tmp_path / "sweep.csv"
    rows = [_row(0, 0.25), _row(1, -0.125)]
    _write(path, rows)
    whole = path.read_bytes()
    path.write_bytes(whole + b"2,1.5,0.0")
    assert _same(sweep.read_rows(path, HEADER), rows)
    assert path.read_bytes() == whole + b"2,1.5,0.0"
    assert _same(sweep.read_rows(path, HEADER, repair=True), rows)
    assert path.read_bytes() == whole
    _write(path, [_row(3, 0.5, completed=False, error="refused")])
    back = sweep.read_rows(path, HEADER)
    assert _same(back[:2], rows) and back[2]["sample"] == 3 and back[2]["error"] == "refused"
    assert _same(back[2:], [_row(3, 0.5, completed=False, error="refused")])
    assert back[2]["completed"] is False and back[2]["wall_s"] == 6.0


def test_another_sweeps_file_is_refused_and_an_empty_or_header_only_one_has_no_rows(tmp_path):
    """Catches a resume from another sweep's file (other parameters), or a header torn by a kill read as
    rows."""
    path = tmp_path / "sweep.csv"
    path.write_bytes(b"")
    assert sweep.read_rows(path, HEADER) == []
    path.write_bytes(b"sample,drive1.R")                  # killed while writing the header
    assert sweep.read_rows(path, HEADER, repair=True) == [] and path.read_bytes() == b""
    _write(path, [_row(0, 0.1)])
    with pytest.raises(ValueError, match=r"header \[.*'plant.l0'.*\] is not this sweep's \['sample', 'drive2.R'"):
        sweep.read_rows(path, sweep.columns(["drive2.R", "plant.l0"]))


def test_a_file_in_the_documented_form_reads_back_each_column_as_its_type(tmp_path):
    """sweep.csv as docs/index.md states it, written by hand (the error's fields empty when
    none): each column read back as its kind, an empty error time or value as NaN, an empty
    error code as None, the text columns as text; an empty metric is refused.  Catches the
    reader's column kinds swapped or widened (an empty error time refused, or an empty metric
    taken as NaN: a torn or hand-edited value passing as "not settled")."""
    path = tmp_path / "sweep.csv"
    done = "0,1.25,0.05,0.5,0.02,nan,0.3,1.5,true,completed,,,,,,,,,3.0"
    failed = "1,1.5,0.049,nan,nan,nan,nan,nan,false,refused,plant,0.25,q1,-7.5,rad,3,absurd,plant refused,4.0"
    path.write_text(",".join(HEADER) + "\n" + done + "\n" + failed + "\n")
    first, second = sweep.read_rows(path, HEADER)
    assert first["sample"] == 0 and first["completed"] is True and first["outcome"] == "completed"
    assert (first["drive1.R"], first["plant.l0"], first["e_ef_mm"], first["wall_s"]) == (1.25, 0.05, 0.5, 3.0)
    assert math.isnan(first["error_time"]) and math.isnan(first["error_value"]) and math.isnan(first["e_ss_mm"])
    assert first["error_code"] is None
    assert [first[k] for k in ("error_instance", "error_variable", "error_unit", "error_reason", "error")] == [""] * 5
    assert second["completed"] is False and second["error_code"] == 3
    assert (second["error_time"], second["error_value"]) == (0.25, -7.5)
    assert [second[k] for k in ("outcome", "error_instance", "error_variable", "error_unit", "error_reason",
                                "error")] == ["refused", "plant", "q1", "rad", "absurd", "plant refused"]
    assert [type(second[k]) for k in HEADER] == [int, float, float, float, float, float, float, float, bool, str,
                                                 str, float, str, float, str, int, str, str, float]
    path.write_text(",".join(HEADER) + "\n" + done.replace(",0.5,", ",,") + "\n")
    with pytest.raises(ValueError, match="could not convert string to float: ''"):
        sweep.read_rows(path, HEADER)


def test_the_statistics_are_numpys_over_the_completed_finite_values():
    """n, mean, sample std (ddof 1), min, the 5/50/95 % percentiles, max of each metric over
    the completed rows whose value is finite; a metric with no value has n = 0; one value has
    std 0.  Catches failed rows counted, NaN kept, the population std, percentiles swapped."""
    rows = [_row(k, 0.1 * k * (-1) ** k) for k in range(9)] + [_row(9, 5.0, completed=False, error="x")]
    s = sweep.summarize(rows)
    assert (s["samples"], s["completed"], s["failed"]) == (10, 9, 1)
    assert list(s["outcomes"].items()) == [("completed", 9), ("refused", 1)]     # RunStatus' words, its order
    for metric in sweep.METRICS:
        v = [r[metric] for r in rows[:9] if math.isfinite(r[metric])]
        assert s[metric]["n"] == len(v)
        mean = sum(v) / len(v)
        std = math.sqrt(sum((x - mean) ** 2 for x in v) / (len(v) - 1))
        ordered = sorted(v)

        def percentile(p):         # numpy's default: linear between the closest ranks
            rank = p / 100 * (len(ordered) - 1)
            low = math.floor(rank)
            return ordered[low] + (rank - low) * (ordered[min(low + 1, len(ordered) - 1)] - ordered[low])

        expected = {"mean": mean, "std": std, "min": ordered[0], "p05": percentile(5), "median": percentile(50),
                    "p95": percentile(95), "max": ordered[-1]}
        for key, value in expected.items():
            assert s[metric][key] == pytest.approx(value, rel=1e-12, abs=1e-15), (metric, key)
    assert s["e_ss_mm"]["n"] == 8                           # sample 2's NaN left out
    one = sweep.summarize([_row(0, 0.2), _row(1, 0.3, completed=False)])
    assert one["e_ef_mm"] == {"n": 1, "mean": 0.7, "std": 0.0, "min": 0.7, "p05": 0.7, "median": 0.7,
                              "p95": 0.7, "max": 0.7}
    assert sweep.summarize([_row(2, 0.2)])["e_ss_mm"] == {"n": 0}


def test_summary_md_states_the_settings_and_each_statistic_to_four_digits():
    """Catches summary.md stating other settings or counts than the sweep's, statistics to other digits, or
    a failed sample left out of its list."""
    rows = [_row(0, 0.2), _row(1, 0.4), _row(2, 0.1, completed=False, error="drive1: refused at t = 0.5 s")]
    result = sweep.Sweep("bench_circle_TCMDx", ["drive1.R", "plant.l0"], rows, sweep.summarize(rows), [0, 1, 2],
                         {"uncertainty": 0.25, "distribution": "normal", "seed": 7, "mode": "inprocess"})
    text = sweep.summary_markdown(result)
    lines = text.splitlines()
    assert lines[0] == "# Sweep of bench_circle_TCMDx"
    assert lines[2] == ("U = 0.25 (normal), seed 7, mode inprocess; 3 samples, 2 completed, 1 failed; "
                        "2 perturbed parameters.")
    e_ef = next(line for line in lines if line.startswith("| e_ef_mm |")).strip("| ").split(" | ")
    values = [0.7, 0.9]
    std = math.sqrt(((0.7 - 0.8) ** 2 + (0.9 - 0.8) ** 2) / 1)
    assert e_ef[1] == "2" and [float(x) for x in e_ef[2:]] == pytest.approx(
        [0.8, std, 0.7, float(np.percentile(values, 5)), 0.8, float(np.percentile(values, 95)), 0.9], rel=5e-4)
    assert "| e_ss_1s_mm | 2 | 0.3 | 0 | 0.3 | 0.3 | 0.3 | 0.3 | 0.3 |" in lines
    assert lines[-1] == "* 2: drive1: refused at t = 0.5 s" and text.endswith("\n")
    assert result.column("wall_s").tolist() == [3.0, 4.0, 5.0]


def test_a_scene_cut_short_ends_there_and_no_later_than_its_own_end():
    scene = get_scene("bench_circle_TCMDx")
    assert sweep.with_stop_time(scene, None) is scene
    short = sweep.with_stop_time(scene, 2)
    assert short.system.stop_time == 2.0 and isinstance(short.system.stop_time, float)
    assert sweep.with_stop_time(scene, 11.0).system.stop_time == 11.0
    for bad in (0.0, -1.0, 11.5, math.nan, "2"):
        with pytest.raises(ValueError, match=r"stop_time = .* s must be in \(0, 11\] \(the scene's own end\)"):
            sweep.with_stop_time(scene, bad)


def test_summary_md_reads_back_line_for_line_with_at_most_20_failed_samples():
    """The whole text against one written here from its docstring: the heading, the settings line,
    the table's header and one row per metric (n = 0 with empty cells when no value is finite),
    then a blank line, "Failed samples:", a blank line and the first 20 failed samples of 23 in
    sample order; no such section when none failed.  Catches the section's heading or blank lines
    dropped, more or fewer than 20 listed, the list out of order, a metric row missing or moved."""
    good = [_row(k, 0.1 * k) for k in range(3)]
    for r in good:
        r["t_settle_s"] = math.nan                             # no run settled: n = 0
    failed = [_row(3 + k, 0.5, completed=False, error=f"drive1: refused at t = {k} s") for k in range(23)]
    rows = good + failed
    settings = {"uncertainty": 0.5, "distribution": "uniform", "seed": 3, "mode": "compiled"}
    text = sweep.summary_markdown(sweep.Sweep("bench_circle_PDx", ["drive1.R"], rows, sweep.summarize(rows),
                                              [], settings))
    table = []
    for metric in sweep.METRICS:
        v = np.array([r[metric] for r in good if math.isfinite(r[metric])])
        if not len(v):
            table.append(f"| {metric} | 0 | | | | | | | |")
            continue
        stats = (v.mean(), v.std(ddof=1), v.min(), np.percentile(v, 5), np.median(v), np.percentile(v, 95), v.max())
        table.append(f"| {metric} | {len(v)} | " + " | ".join(f"{x:.4g}" for x in stats) + " |")
    expected = ["# Sweep of bench_circle_PDx", "",
                "U = 0.5 (uniform), seed 3, mode compiled; 26 samples, 3 completed, 23 failed; 1 perturbed parameters.",
                "", "| metric | n | mean | std | min | 5 % | median | 95 % | max |",
                "|---|---|---|---|---|---|---|---|---|",
                *table, "", "Failed samples:", "", *(f"* {3 + k}: drive1: refused at t = {k} s" for k in range(20))]
    assert text == "\n".join(expected) + "\n"
    assert "| t_settle_s | 0 | | | | | | | |" in expected
    clean = sweep.summary_markdown(sweep.Sweep("bench_circle_PDx", ["drive1.R"], good, sweep.summarize(good), [],
                                               settings))
    assert clean.splitlines()[-1] == table[-1] and "Failed" not in clean


@pytest.mark.parametrize("umask", [0o022, 0o077], ids=["umask-022", "umask-077"])
def test_a_new_sweep_csv_is_readable_by_all_but_written_by_its_owner_only_under_the_umask(tmp_path, umask):
    """sweep.csv is created rw-r--r-- (0o644: a results file others may read, only the sweep
    appends), less what the umask takes away; an existing file keeps its mode.  Catches
    another creation mode (execute or sticky bits, a group-writable file) and a mode forced
    on a file the user made (seed 3901 [131])."""
    import os
    import stat

    path = tmp_path / "sweep.csv"
    old = os.umask(umask)
    try:
        _write(path, [_row(0, 0.25)])
    finally:
        os.umask(old)
    assert stat.S_IMODE(path.stat().st_mode) == 0o644 & ~umask
    path.chmod(0o600 if umask == 0o022 else 0o664)
    kept = stat.S_IMODE(path.stat().st_mode)
    _write(path, [_row(1, 0.5)])
    assert stat.S_IMODE(path.stat().st_mode) == kept and len(sweep.read_rows(path, HEADER)) == 2
