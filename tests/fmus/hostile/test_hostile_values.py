"""The values fmus/hostile/cases.py draws (``_value``) and the worker's sanitizer environment
(``sanitizer_env``), checked against their docstrings: a sane value lies within ``spread`` of
its start on both sides, a hostile one is one of the lists; a sanitizer runtime is taken only
as an absolute path that exists."""
from __future__ import annotations

import math
import random
import stat
import sys

import pytest

from fmus.hostile import cases
from fmus.hostile.cases import (ASAN_EXIT, HOSTILE_INTEGERS, HOSTILE_REALS, HOSTILE_STRINGS, START_TIMES, STEP_SIZES,
                                UBSAN_EXIT, _value)


@pytest.mark.parametrize("start, spread", [(2.0, 0.5), (-4.0, 0.5), (10.0, 0.02)])
def test_a_sane_real_covers_the_whole_spread_on_both_sides_of_its_start(start, spread):
    """Without hostility a Real is start * U(1 - spread, 1 + spread) plus a tiny absolute jitter:
    about half above the start and half below, reaching both ends of the band."""
    rng = random.Random(1)
    values = [_value(rng, "Real", start, 0.0, spread) for _ in range(4000)]
    jitter = 0.01 * spread * abs(start)
    lo, hi = sorted((start * (1 - spread), start * (1 + spread)))
    assert all(lo - jitter <= v <= hi + jitter for v in values)
    above = sum(v > start for v in values) / len(values)
    assert 0.45 < above < 0.55, above
    width = hi - lo
    assert min(values) < lo + 0.05 * width and max(values) > hi - 0.05 * width


def test_a_real_without_a_finite_start_is_drawn_around_zero_within_the_jitter():
    """start None, nan or inf: the base is 0, so only the absolute jitter (0.01 * spread) is left."""
    rng = random.Random(2)
    for start in (None, math.nan, math.inf):
        values = [_value(rng, "Real", start, 0.0) for _ in range(500)]
        assert all(abs(v) <= 0.005 for v in values) and min(values) < -0.004 and max(values) > 0.004


def test_hostile_values_come_from_the_lists_at_the_given_rate():
    """hostile = 1: every Real, Integer and String is one of the hostile lists; hostile = 0.3:
    about 30 % of the Reals are."""
    rng = random.Random(3)
    for _ in range(300):
        r = _value(rng, "Real", 1.0, 1.0)
        assert any(r == h or (math.isnan(r) and math.isnan(h)) for h in HOSTILE_REALS)
        assert _value(rng, "Integer", 5, 1.0) in HOSTILE_INTEGERS
        assert _value(rng, "String", "exact", 1.0) in HOSTILE_STRINGS
    share = sum(not 0.4 <= _value(rng, "Real", 1.0, 0.3) <= 1.6 for _ in range(4000)) / 4000
    assert 0.26 < share < 0.34, share


def test_sane_integers_strings_and_booleans_stay_by_their_start():
    """An Integer is start + each of -2..2 (start None: 0); a String its start ("" for None);
    a Boolean either value, about half each."""
    rng = random.Random(4)
    assert {_value(rng, "Integer", 7, 0.0) for _ in range(400)} == {5, 6, 7, 8, 9}
    assert {_value(rng, "Integer", None, 0.0) for _ in range(400)} == {-2, -1, 0, 1, 2}
    assert {_value(rng, "String", "tabulated", 0.0) for _ in range(50)} == {"tabulated"}
    assert {_value(rng, "String", None, 0.0) for _ in range(50)} == {""}
    trues = sum(_value(rng, "Boolean", False, 0.0) for _ in range(2000)) / 2000
    assert 0.45 < trues < 0.55


def fake_compiler(tmp_path, monkeypatch, answers: dict):
    """A 'compiler' whose ``-print-file-name=NAME`` prints ``answers[NAME]`` (else NAME, as gcc
    does for a file it does not find), put in place of kernels.build.compiler."""
    from kernels import build

    lines = "\n".join(f'  -print-file-name={name}) echo "{path}" ;;' for name, path in answers.items())
    script = tmp_path / "cc"
    script.write_text(f'#!/bin/sh\ncase "$1" in\n{lines}\n  *) echo "${{1#-print-file-name=}}" ;;\nesac\n')
    script.chmod(script.stat().st_mode | stat.S_IXUSR)
    monkeypatch.setattr(build, "compiler", lambda: str(script))


def test_the_sanitizer_environment_preloads_the_runtimes_the_compiler_finds(tmp_path, monkeypatch):
    """Both runtimes found (absolute paths that exist): LD_PRELOAD is ASan's then libstdc++'s,
    and the options end a worker with the sanitizers' own exit statuses, logs under log_dir."""
    asan, cxx = tmp_path / "libasan.so", tmp_path / "libstdc++.so.6"
    asan.write_bytes(b""), cxx.write_bytes(b"")
    fake_compiler(tmp_path, monkeypatch, {"libasan.so": asan, "libstdc++.so.6": cxx})
    env = cases.sanitizer_env(tmp_path / "logs")
    assert env["LD_PRELOAD"] == f"{asan} {cxx}" and env["PYTHONMALLOC"] == "malloc"
    logs = (tmp_path / "logs").resolve()
    assert logs.is_dir()
    assert env["ASAN_OPTIONS"] == f"detect_leaks=0:exitcode={ASAN_EXIT}:log_path={logs / 'asan'}"
    assert env["UBSAN_OPTIONS"] == f"halt_on_error=1:print_stacktrace=1:exitcode={UBSAN_EXIT}:log_path={logs / 'ubsan'}"
    fake_compiler(tmp_path, monkeypatch, {"libasan.so": asan})      # no libstdc++: ASan's alone, no logs
    env = cases.sanitizer_env()
    assert env["LD_PRELOAD"] == str(asan) and env["ASAN_OPTIONS"] == f"detect_leaks=0:exitcode={ASAN_EXIT}"


@pytest.mark.parametrize("answer", ["absolute, missing", "relative, present"])
def test_a_runtime_that_is_not_an_existing_absolute_path_is_not_found(answer, tmp_path, monkeypatch):
    """gcc prints the bare name of a file it does not find: a relative name is no runtime even
    when the working directory happens to hold a file of that name, nor is an absolute path
    that does not exist; without ASan's runtime the environment is refused."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "libasan.so").write_bytes(b"")
    path = tmp_path / "gone" / "libasan.so" if answer.startswith("absolute") else "libasan.so"
    fake_compiler(tmp_path, monkeypatch, {"libasan.so": path})
    with pytest.raises(RuntimeError, match="no AddressSanitizer runtime"):
        cases.sanitizer_env()


def test_the_hostile_reals_are_distinct_and_come_with_both_signs():
    """Every hostile real but NaN has its negative in the list too (zero as -0.0, the smallest
    normal and subnormal, the largest doubles, infinity), and no value is listed twice, so each
    sign of each magnitude is drawn.  Catches a sign flipped into a duplicate (training seed
    4322 [23]: -1e-300 -> 1e-300 left 1e-300 twice and no -1e-300)."""
    keys = [(math.copysign(1.0, x), abs(x)) for x in HOSTILE_REALS if not math.isnan(x)]
    assert len(set(keys)) == len(keys)
    assert all((-sign, magnitude) in keys for sign, magnitude in keys
               if magnitude in (0.0, 1e-300, 5e-324, 1e300, sys.float_info.max, math.inf, 1.0))
    assert sum(math.isnan(x) for x in HOSTILE_REALS) == 1


def test_the_hostile_integers_reach_both_ends_of_a_32_bit_fmi2_integer_and_stay_inside():
    """fmi2Integer is a C ``int`` (32 bits on every FMI platform): the hostile integers hold its
    minimum -2**31 and maximum 2**31 - 1 exactly and nothing outside (a value outside would be
    refused by ctypes or wrapped, never reaching the FMU as drawn)."""
    assert min(HOSTILE_INTEGERS) == -2 ** 31 and max(HOSTILE_INTEGERS) == 2 ** 31 - 1
    assert all(isinstance(i, int) and -2 ** 31 <= i <= 2 ** 31 - 1 for i in HOSTILE_INTEGERS)


def test_the_hostile_reals_and_step_sizes_reach_the_ends_of_a_double():
    """The smallest subnormal (``math.ulp(0.0)``) with both signs, the largest finite double with
    both signs and both infinities are hostile reals; a step size is drawn as that subnormal, 0,
    a negative, NaN and infinity too.  Catches an end of the double range moved inward."""
    tiny, big = math.ulp(0.0), sys.float_info.max
    assert {tiny, -tiny, big, -big, math.inf, -math.inf} <= set(HOSTILE_REALS)
    assert {tiny, 0.0, math.inf} <= set(STEP_SIZES) and any(h < 0 for h in STEP_SIZES)
    assert any(math.isnan(h) for h in STEP_SIZES)


def test_the_start_times_hold_both_kinds_fmi2setupexperiment_must_refuse_and_sane_ones():
    """START_TIMES' docstring: a start time not finite, or where t0 + 1e-6 == t0, must be refused.
    Both kinds are there (each infinity, NaN, and a finite t0 that 1e-6 no longer moves), with
    finite times that 1e-6 does move (0, a negative one)."""
    finite = [t for t in START_TIMES if math.isfinite(t)]
    assert math.inf in START_TIMES and -math.inf in START_TIMES and any(math.isnan(t) for t in START_TIMES)
    assert any(t + 1e-6 == t for t in finite) and 0.0 in finite and any(t < 0 and t + 1e-6 != t for t in finite)
