"""The hostile-use campaign against FMUs built with AddressSanitizer and
UndefinedBehaviorSanitizer (issue 28, item 5).

Cases come from :func:`scenarios.hostile.make_case` and run in worker subprocesses with the
ASan runtime preloaded (:func:`scenarios.hostile.sanitizer_env`): an out-of-bounds access,
a use after free or undefined behaviour in an FMU ends its worker, and the case is a crash.
First the harness itself: the C low-pass of benchmarks/baseline_fmu with its instance
allocated 8 bytes short is a crash in every case, and is clean when allocated right.
"""
from __future__ import annotations

import subprocess
import zipfile
from pathlib import Path

import pytest

from scenarios import hostile

#: Links into the low-pass a calloc that returns 8 bytes whatever is asked: its instance
#: is written past its end in fmi2Instantiate.
SHORT_CALLOC = """#include <stddef.h>
void *__real_calloc(size_t n, size_t size);
void *__wrap_calloc(size_t n, size_t size) { (void)n; (void)size; return __real_calloc(1, 8); }
"""


def _sanitizer_env_or_skip(log_dir):
    try:
        return hostile.sanitizer_env(log_dir)
    except Exception as exc:  # noqa: BLE001 - no compiler, no runtime
        pytest.skip(f"no AddressSanitizer runtime here: {exc}")


def sanitized_lowpass(out: Path, short_allocation: bool) -> Path:
    """The low-pass FMU built with the kernels' sanitizer flags (kernels.build.SANITIZE)."""
    import fmpy

    from benchmarks.cold_start import BASELINE_DIR
    from kernels import build

    headers = Path(fmpy.__file__).resolve().parent / "c-code"
    sources = [str(BASELINE_DIR / "lowpass.c")]
    if short_allocation:
        (out / "short_calloc.c").write_text(SHORT_CALLOC)
        sources += [str(out / "short_calloc.c"), "-Wl,--wrap=calloc"]
    library = out / "lowpass.so"
    subprocess.run([build.compiler(), "-std=c11", "-fPIC", "-shared", *build.SANITIZE, f"-I{headers}", *sources,
                    "-o", str(library), "-lm"], check=True, capture_output=True)
    path = out / "LowPass.fmu"
    with zipfile.ZipFile(path, "w") as z:
        z.write(BASELINE_DIR / "modelDescription.xml", "modelDescription.xml")
        z.write(library, "binaries/linux64/lowpass.so")
    return path


def sane_lowpass_case(seed: int) -> dict:
    """A case of plain use (the baseline low-pass is no hardened FMU: under hostile cases it
    gives NaN with fmi2OK, and its log calls read the instance name fmpy freed, which FMI 2.0
    requires an FMU to copy; docs/extremes.md)."""
    ops = [op for k in range(3) for op in (["set", "u", 1.0 + k], ["step", None, 1e-3], ["get"])]
    return {"model": "LowPass", "kind": "inputs", "seed": seed, "instance_name": "instance", "logging": True,
            "start_time": 0.0, "guid": "own", "parameters": [["tau", 0.02]], "ops": ops}


@pytest.mark.parametrize("short_allocation", (False, True))
def test_the_sanitized_campaign_sees_an_fmu_write_past_its_allocation(tmp_path, short_allocation):
    env = _sanitizer_env_or_skip(tmp_path / "logs")
    fmu = sanitized_lowpass(tmp_path, short_allocation)
    unzipped = hostile.extract_fmus({"LowPass": fmu}, tmp_path / "fmus")
    results = hostile.run_cases([sane_lowpass_case(seed) for seed in range(4)], unzipped, env=env)
    reports = sorted((tmp_path / "logs").glob("asan.*"))
    if short_allocation:
        assert [r.outcome for r in results] == ["crash"] * 4
        assert all(f"exit status {hostile.ASAN_EXIT}" in r.problems[0] for r in results)
        assert "heap-buffer-overflow" in reports[0].read_text()
    else:
        assert [r.outcome for r in results] == ["ok"] * 4 and not reports
