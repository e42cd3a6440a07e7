"""``parcosim identify-motor`` (motor/cli.py): every option takes effect, and its help writes each
option as the reference (docs/index.md) does."""

import json
import re

import pytest

from motor import identify, read_motor_csv
from motor.cli import _parser, identify_main
from motor.identification import MEASURED_L, inertia_from_pole, pole_from_settling_time
from tests.support.paths import ROOT

DATA = ROOT / "motor" / "data"


def _run(capsys, *options):
    assert identify_main(["--data", str(DATA / "motor1.csv"), *options]) == 0
    return json.loads(capsys.readouterr().out)


def test_each_option_reaches_the_identification(capsys):
    """Catches an identify-motor option that is parsed but not passed on (or passed as another):
    --kt-over-ke is kt / ke (D.6), --inductance is the L of (D.16) and --settling-time its t_98%,
    each held against the appendix-D relations with values other than the defaults."""
    u, i, omega = read_motor_csv(DATA / "motor1.csv")
    out = _run(capsys, "--kt-over-ke", "1.25", "--settling-time", "0.15", "--inductance", "0.002")
    assert out["kt_over_ke"] == 1.25 and out["kt"] == 1.25 * out["ke"]
    assert out["L"] == 0.002 and out["settling_time"] == 0.15
    pole = pole_from_settling_time(0.15)
    assert out["pole"] == pole
    assert out["J"] == inertia_from_pole(pole, out["R"], 0.002, out["kt"], out["ke"], out["b"])
    assert out == identify(u, i, omega, kt_over_ke=1.25, settling_time=0.15, L=0.002)
    default_l = _run(capsys, "--kt-over-ke", "1.25", "--settling-time", "0.15")
    assert default_l["L"] == MEASURED_L and default_l["J"] != out["J"]   # the inductance changed J


def _reference_rows():
    """The ``--option METAVAR`` of each row of docs/index.md's identify-motor table."""
    text = (ROOT / "docs" / "index.md").read_text(encoding="utf-8")
    table = text.split("`parcosim identify-motor`", 1)[1].split("\n\n")[1]
    return re.findall(r"^\| `(--[a-z-]+)(?: ([A-Za-z.]+))?` \| ([^|]*) \|", table, flags=re.M)


def test_the_help_writes_each_option_with_its_metavar_and_default_as_the_reference():
    """Catches an option whose help shows another placeholder than the reference's (a dropped
    ``metavar`` prints ``--inductance INDUCTANCE``) or another default."""
    rows = _reference_rows()
    assert {option for option, _, _ in rows} == {"--data", "--kt-over-ke", "--settling-time", "--inductance"}
    parser = _parser()
    actions = {a.option_strings[0]: a for a in parser._actions if a.option_strings}
    help_text = parser.format_help()
    for option, metavar, default in rows:
        assert f"{option} {metavar}" in help_text, (option, metavar)
        assert actions[option].metavar == metavar
        stated = default.strip().removeprefix("default: ")
        if stated == "required":
            assert actions[option].required
        elif stated == "none":
            assert actions[option].default is None
        else:
            assert actions[option].default == pytest.approx(float(stated), rel=1e-5), option


def test_help_exits_0_with_the_usage_on_stdout_and_nothing_on_stderr(capsys):
    """``--help`` (alone or after other options) returns 0, prints the parser's help (no JSON,
    nothing identified) and no error.  Catches a help exit turned into a failure status or
    None, or one that goes on to read the data."""
    for argv in (["--help"], ["--data", str(DATA / "motor1.csv"), "-h"]):
        assert identify_main(argv) == 0
        out, err = capsys.readouterr()
        assert out == _parser().format_help() and err == ""


@pytest.mark.parametrize("argv, words", [
    ([], "the following arguments are required: --data"),
    (["--data", str(DATA / "motor1.csv"), "--kt-over-ke", "x"], "argument --kt-over-ke: invalid float value: 'x'"),
    (["--data", str(DATA / "motor1.csv"), "--bogus"], "unrecognized arguments: --bogus"),
    (["--data", str(DATA / "motor1.csv"), "--kt-over-ke", "-1"], "kt_over_ke must be > 0, got -1.0"),
    (["--data", str(DATA / "motor1.csv"), "--settling-time", "0"], "settling_time must be > 0, got 0.0"),
])
def test_a_bad_argument_or_value_exits_2_with_one_error_line(capsys, argv, words):
    """The docstring's contract: 2 and exactly one line ``parcosim identify-motor: error: ...``
    on stderr, nothing on stdout.  Catches argparse's multi-line usage error (or its exit)
    leaking through, a status other than 2, or a result printed after an error."""
    assert identify_main(argv) == 2
    out, err = capsys.readouterr()
    assert out == "" and err == f"parcosim identify-motor: error: {words}\n"


def test_a_missing_file_exits_2_naming_it(capsys, tmp_path):
    """Catches a missing data file that raises (an OSError traceback) instead of the one line."""
    missing = tmp_path / "none.csv"
    assert identify_main(["--data", str(missing)]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.startswith(f"parcosim identify-motor: error: cannot read {missing}: ")
    assert err.count("\n") == 1
