"""Build and run the C host of ``host.c`` (libcosim's C API, no Python in its process).

:func:`build_host` compiles ``host.c`` against the ``libcosimc.so`` that the libcosimpy
wheel ships (its header is not shipped: ``cosim_api.h`` declares the functions used);
:func:`run_host` writes a configuration, runs the host and returns its CSV and its report
(:class:`HostRun`).  Used by tests/fmus/native/test_native_host.py and benchmarks/native_speed.py.
"""
from __future__ import annotations

import csv
import os
import shutil
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

HERE = Path(__file__).resolve().parent
FLAGS = ("-std=c11", "-O2", "-Wall", "-Wextra", "-Werror", "-Wshadow")


class HostUnavailable(RuntimeError):
    """No C compiler, or no libcosimc.so (libcosimpy not installed)."""


def libcosimc_path() -> Path:
    """The ``libcosimc.so`` inside the installed libcosimpy wheel."""
    try:
        import libcosimpy
    except ImportError as exc:
        raise HostUnavailable(f"libcosimpy is not installed ({exc}): pip install libcosimpy") from exc
    path = Path(libcosimpy.__file__).resolve().parent / "libcosimc" / "libcosimc.so"
    if not path.is_file():
        raise HostUnavailable(f"no libcosimc.so in the libcosimpy wheel (looked for {path})")
    return path


def build_host(out_dir) -> Path:
    """Compile the host into ``out_dir/host`` (rpath to the wheel's libcosimc.so)."""
    compiler = shutil.which(os.environ.get("CC", "")) or shutil.which("cc") or shutil.which("gcc")
    if compiler is None:
        raise HostUnavailable("no C compiler (cc or gcc)")
    library = libcosimc_path()
    program = Path(out_dir) / "host"
    subprocess.run([compiler, *FLAGS, str(HERE / "host.c"), "-o", str(program), str(library),
                    f"-Wl,-rpath,{library.parent}", "-ldl"], check=True, capture_output=True, text=True)
    return program


@dataclass
class HostRun:
    """What one host run printed (``report``: key -> text) and wrote (``columns``: name -> values)."""

    report: dict
    columns: dict = field(default_factory=dict)

    def number(self, key: str) -> float:
        return float(self.report[key])

    @property
    def fmu_binaries(self) -> list:
        text = self.report.get("fmu_binaries", "-")
        return [] if text == "-" else text.split(",")


def config_text(stop: float, outputs=(), ssp=None, step=None, slaves=(), connections=(), reals=(),
                every: int = 1) -> str:
    """The host's configuration (``host.c``'s header): ``slaves`` (name, fmu path),
    ``connections`` ("a.y", "b.u"), ``reals`` ("a.u", value), ``outputs`` "slave.variable"."""
    lines = [f"ssp {ssp}"] if ssp else [f"step {step!r}"]
    lines += [f"slave {name} {path}" for name, path in slaves]
    lines += [f"connect {a} {b}" for a, b in connections]
    lines += [f"real {name} {float(value)!r}" for name, value in reals]
    lines += [f"output {name}" for name in outputs]
    lines += [f"stop {float(stop)!r}", f"every {int(every)}"]
    return "\n".join(lines) + "\n"


def run_host(program, work_dir, config: str, env=None, timeout: float = 600.0) -> HostRun:
    """Run ``program`` on ``config`` in ``work_dir``; raise RuntimeError with its stderr if it fails."""
    work = Path(work_dir)
    work.mkdir(parents=True, exist_ok=True)
    (work / "host.cfg").write_text(config, encoding="utf-8")
    out = work / "out.csv"
    run = subprocess.run([str(program), str(work / "host.cfg"), str(out)], capture_output=True, text=True,
                         env=env, timeout=timeout)
    if run.returncode != 0:
        raise RuntimeError(f"the C host failed (exit {run.returncode}): {run.stderr.strip()[-2000:]}")
    report = dict(line.split(" ", 1) for line in run.stdout.splitlines() if " " in line)
    with open(out, newline="", encoding="utf-8") as f:
        rows = list(csv.reader(f))
    columns = {name: [float(row[i]) for row in rows[1:]] for i, name in enumerate(rows[0])}
    return HostRun(report, columns)
