"""The native FMUs' C (generic part, state parser, adapters) under AddressSanitizer and
UBSan: each FMU is rebuilt from its sources with the sanitizers and driven by
tests/support/native_fuzz.py in a subprocess: careless calls, every truncation of a saved
state and 300 forged ones whose checksum is made right, so the parser's checks past the
checksum are reached; the position controller's steps run its law, on its table and off it
(the exact model's fallback).  Wrong code it catches: a read past the state's end, a string length
taken on trust, a slot out of range, undefined arithmetic."""
from __future__ import annotations

import json
import subprocess
import sys
import zipfile

import pytest

from fmus.native.build import compile_command, platform_folder
from fmus.native.models import NATIVE
from tests.kernels.test_sanitizers import ASAN, _sanitized_env
from tests.support.paths import ROOT, TESTS

SANITIZE = ("-fsanitize=address,undefined", "-fno-sanitize-recover=all", "-fno-omit-frame-pointer", "-g")
pytestmark = [pytest.mark.slow, pytest.mark.fmu, pytest.mark.tools,
              pytest.mark.skipif(ASAN is None, reason="the C compiler has no AddressSanitizer runtime")]


@pytest.mark.parametrize("model", sorted(NATIVE) + ["ClosedLoop"])
def test_native_fmu_survives_careless_calls_and_forged_states_under_asan(model, request, tmp_path):
    """Catches an out-of-bounds access, use after free or undefined behaviour in a native FMU under
    careless calls and forged states, which only the sanitizers see."""
    fmu = request.getfixturevalue("native_loop_fmu") if model == "ClosedLoop" else \
        request.getfixturevalue("native_fmus")[model]
    folder = tmp_path / "fmu"
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    binary = folder / "binaries" / platform_folder() / f"{model}.so"
    command = compile_command(folder / "sources", binary)
    subprocess.run([command[0], *SANITIZE, *command[1:]], check=True, capture_output=True)
    worker = TESTS / "support" / "native_fuzz.py"
    env = _sanitized_env(binary)
    env["PYTHONPATH"] = str(ROOT)
    rows = []
    if model == "PositionController":   # steps the law runs: on the table, then off it (the exact fallback)
        from tests.fmus.native.test_native_equality import _controller_inputs

        inputs = _controller_inputs()
        rows = [tmp_path / "inputs.json"]
        rows[0].write_text(json.dumps([inputs(90 + k, (90 + k) * 1e-3) for k in range(30)]))
    run = subprocess.run([sys.executable, str(worker), str(folder), "28", *map(str, rows)], env=env,
                         capture_output=True, text=True, errors="backslashreplace", timeout=300)
    assert run.returncode == 0 and "survived" in run.stdout, run.stderr[-3000:]
    if rows:
        assert "30 of 30 steps accepted" in run.stdout, run.stdout[-300:]
