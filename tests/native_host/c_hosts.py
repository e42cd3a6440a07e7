"""Build and run two more C hosts, no Python in their process: ``fmi2_host.c`` (a plain FMI
2.0 Jacobi host of our own: dlopen and the fmi2 functions, nothing else) and ``ecos_host.c``
(an SSP package stepped by Ecos's C library ``libecosc.so`` from the ecospy wheel).

:func:`plain_config` writes the plain host's configuration from FMU files or from an SSP
package (:func:`ssp_parts`: its components and connections; it sets no parameters, as fmpy's
SSP runner: the per-component native FMUs carry theirs compiled in).
:func:`one_fmu_package` wraps one FMU as an SSP package whose OSP annotation sets libcosim's
worker threads (libcosimc's API has no other way to set them).  Used by
benchmarks/native_c_hosts.py and tests/fmus/native/test_native_c_hosts.py.
"""
from __future__ import annotations

import os
import shutil
import subprocess
import zipfile
from pathlib import Path

from tests.native_host.host import FLAGS, HostRun, HostUnavailable

HERE = Path(__file__).resolve().parent


def _compiler() -> str:
    compiler = shutil.which(os.environ.get("CC", "")) or shutil.which("cc") or shutil.which("gcc")
    if compiler is None:
        raise HostUnavailable("no C compiler (cc or gcc)")
    return compiler


def build_fmi2_host(out_dir) -> Path:
    """Compile ``fmi2_host.c`` into ``out_dir/fmi2_host`` (fmpy's FMI 2.0 headers)."""
    from fmus.native.build import fmi_headers

    program = Path(out_dir) / "fmi2_host"
    subprocess.run([_compiler(), *FLAGS, f"-I{fmi_headers()}", str(HERE / "fmi2_host.c"), "-o", str(program), "-ldl"],
                   check=True, capture_output=True, text=True)
    return program


def libecosc_path() -> Path:
    """The ``libecosc.so`` inside the installed ecospy wheel."""
    try:
        import ecospy
    except (ImportError, OSError) as exc:
        raise HostUnavailable(f"ecospy cannot be loaded ({exc}): pip install ecospy") from exc
    path = Path(ecospy.__file__).resolve().parent / "binaries" / "libecosc.so"
    if not path.is_file():
        raise HostUnavailable(f"no libecosc.so in the ecospy wheel (looked for {path})")
    return path


def build_ecos_host(out_dir) -> Path:
    """Compile ``ecos_host.c`` into ``out_dir/ecos_host`` (rpath to the wheel's libecosc.so)."""
    library = libecosc_path()
    program = Path(out_dir) / "ecos_host"
    subprocess.run([_compiler(), *FLAGS, str(HERE / "ecos_host.c"), "-o", str(program), str(library),
                    f"-Wl,-rpath,{library.parent}"], check=True, capture_output=True, text=True)
    return program


def _unpacked(fmu: Path, into: Path) -> tuple:
    """(binary, model identifier, guid, resources URI, model description) of ``fmu`` unpacked
    into ``into``."""
    from fmpy import extract, read_model_description

    md = read_model_description(str(fmu))
    if md.fmiVersion != "2.0" or md.coSimulation is None:
        raise ValueError(f"{fmu}: the plain host runs FMI 2.0 co-simulation FMUs (fmiVersion {md.fmiVersion})")
    directory = Path(extract(str(fmu), unzipdir=str(into)))
    identifier = md.coSimulation.modelIdentifier
    binary = directory / "binaries" / "linux64" / f"{identifier}.so"
    if not binary.is_file():
        raise ValueError(f"{fmu}: no binaries/linux64/{identifier}.so")
    return binary, identifier, md.guid, (directory / "resources").as_uri(), md


def plain_config(work, step: float, stop: float, fmus: dict, connections=(), outputs=(),
                 profile: bool = False, reals=()) -> str:
    """The plain host's configuration: ``fmus`` instance -> FMU file, ``connections``
    ("a.y", "b.u") of Real variables, ``outputs`` "instance.variable" read every step,
    ``reals`` ("a.u", value) set in Initialization Mode."""
    vrs, lines = {}, [f"step {step!r}", f"stop {float(stop)!r}", f"profile {int(profile)}"]
    for name, fmu in fmus.items():
        binary, identifier, guid, uri, md = _unpacked(Path(fmu), Path(work) / "unpacked" / name)
        vrs[name] = {v.name: v.valueReference for v in md.modelVariables if v.type == "Real"}
        lines.append(f"slave {name} {binary} {identifier} {guid} {uri}")

    def ref(signal):
        instance, variable = signal.split(".", 1)
        if variable not in vrs.get(instance, {}):
            raise ValueError(f"no Real variable {signal} among the FMUs")
        return f"{instance} {vrs[instance][variable]}"

    lines += [f"connect {ref(a)} {ref(b)}" for a, b in connections]
    lines += [f"real {ref(name)} {float(value)!r}" for name, value in reals]
    lines += [f"output {ref(o)}" for o in outputs]
    return "\n".join(lines) + "\n"


def one_fmu_package(fmu: Path, path: Path, step: float, worker_threads: int | None = 0) -> Path:
    """``fmu`` alone as an SSP package at ``path`` (instance ``loop``) whose OSP annotation
    gives ``step`` and ``worker_threads`` (0: libcosim steps the FMU on the calling thread;
    None: its default pool of ``hardware_concurrency - 1`` worker threads)."""
    from fmus.cosim.system import Component, System
    from fmus.ssp.export import export_ssp
    from fmus.ssp.libcosim import with_libcosim_annotation

    fmu, path = Path(fmu), Path(path)
    system = System(components=(Component("loop", fmu.stem),), connections=(), record=(), stop_time=1.0, step=step)
    plain = export_ssp(system, path.with_name(path.stem + "_plain.ssp"), fmus={fmu.stem: fmu}, bake=False)
    return with_libcosim_annotation(plain, path, step, worker_threads)


def ssp_parts(path, into) -> tuple:
    """({instance: FMU file unpacked from the package}, [(from, to)] connections) of an SSP
    package."""
    from fmus.ssp.export import NS, _parse

    with zipfile.ZipFile(path) as zf:
        ssd = _parse(zf, "SystemStructure.ssd")
        fmus = {}
        for component in ssd.iterfind("ssd:System/ssd:Elements/ssd:Component", NS):
            target = Path(into) / "fmus" / f"{component.get('name')}.fmu"
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_bytes(zf.read(component.get("source")))
            fmus[component.get("name")] = target
    links = [(f"{c.get('startElement')}.{c.get('startConnector')}", f"{c.get('endElement')}.{c.get('endConnector')}")
             for c in ssd.iterfind("ssd:System/ssd:Connections/ssd:Connection", NS)]
    return fmus, links


def _report(run: subprocess.CompletedProcess, what: str) -> HostRun:
    if run.returncode != 0:
        raise RuntimeError(f"the {what} failed (exit {run.returncode}): {run.stderr.strip()[-2000:]}")
    return HostRun(dict(line.split(" ", 1) for line in run.stdout.splitlines() if " " in line))


def run_fmi2_host(program, work, config: str, timeout: float = 600.0) -> HostRun:
    """Run the plain host on ``config``; raise RuntimeError with its stderr if it fails."""
    work = Path(work)
    work.mkdir(parents=True, exist_ok=True)
    (work / "fmi2_host.cfg").write_text(config, encoding="utf-8")
    return _report(subprocess.run([str(program), str(work / "fmi2_host.cfg")], capture_output=True, text=True,
                                  timeout=timeout), "plain FMI 2.0 host")


def run_ecos_host(program, package, step: float, stop: float, parameter_set: str | None = None,
                  one_cpu: bool = True, values=(), timeout: float = 600.0) -> HostRun:
    """Run the Ecos host on ``package`` (``values``: "instance.variable" Reals to read at the
    end, reported as ``value.instance::variable``); raise RuntimeError with its stderr if it fails."""
    argv = [str(program), str(package), repr(float(step)), repr(float(stop)), parameter_set or "-", str(int(one_cpu)),
            *(v.replace(".", "::", 1) for v in values)]
    return _report(subprocess.run(argv, capture_output=True, text=True, timeout=timeout), "Ecos host")
