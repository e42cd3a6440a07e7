"""The reproduction report: its numbers come from the runs' metrics, and it says what differs."""
import math

from fmus.status import RunError, RunStatus
from scenarios.batch.report import THESIS_BENCH, bench_scene_names, render


def _metrics(e_ef, stopped=()):
    metrics = {}
    for name in bench_scene_names():
        kind, strategy = name.split("_")[1:]
        done = name not in stopped
        value = e_ef[kind][strategy] if done else math.nan
        metrics[name] = {"completed": done, "e_ef_mm": value, "tau_ef_Nm": 0.1 + value / 100 if done else math.nan,
                         "e_ss_mm": 0.01 if done else math.nan, "e_ss_x_mm": 0.0, "e_ss_y_mm": 0.01,
                         "window_s": [1.0, 8.0], "simulated_s": 9.0, "wall_s": 1.0, "realtime_factor": 9.0,
                         "error": None if done else RunError(RunStatus.REFUSED, "ctrl refused the step from t = 1 s: test",
                                                             "ctrl", 1.0).record()}
    return metrics


def test_report_numbers_come_from_the_metrics():
    """Catches a report that prints stored or thesis numbers instead of the runs' metrics."""
    e_ef = {kind: {s: 2 * v[0] for s, v in table.items()} for kind, table in THESIS_BENCH.items()}
    text = render(_metrics(e_ef), "inprocess")
    assert "| PDq | 6.300 | 3.15 |" in text          # ours = twice the thesis here
    # the MD change is recomputed from our numbers: 2.37/3.15 - 1 = -24.8 %
    assert "| PDq → PDMDq | -24.8 % | -24.9 % |" in text
    assert "lowers e_ef in all 4 pairs" in text
    assert "Our e_ef is 2.00–2.00 times the bench's." in text


def test_report_says_when_sliding_modes_do_not_help_and_when_runs_stopped():
    """Catches the report claiming the sliding-mode term helps where it does not, hiding a stopped run, or
    giving a stopped run's e_ef."""
    e_ef = {kind: {s: v[0] for s, v in table.items()} for kind, table in THESIS_BENCH.items()}
    e_ef["triangle"]["TCMDx"] = 2.0                      # worse than TCx's 1.83
    text = render(_metrics(e_ef, stopped=("bench_circle_TCq",)), "fmu")
    assert "does not lower e_ef for TCx→TCMDx" in text
    assert "Runs stopped early:** bench_circle_TCq: ctrl refused the step from t = 1 s: test" in text
    assert "| TCq | — | 1.14 | — | 0.143 |" in text
    assert "No e_ef for TCq" in text


def test_a_metrics_file_from_before_the_error_record_still_reports_its_message():
    """Catches the report failing on a metrics.json whose ``error`` is the message itself (written
    before the refusal record), instead of printing it."""
    e_ef = {kind: {s: v[0] for s, v in table.items()} for kind, table in THESIS_BENCH.items()}
    metrics = _metrics(e_ef, stopped=("bench_circle_TCq",))
    metrics["bench_circle_TCq"]["error"] = "ctrl refused the step from t = 1 s: old"
    assert "Runs stopped early:** bench_circle_TCq: ctrl refused the step from t = 1 s: old" in render(metrics, "fmu")
