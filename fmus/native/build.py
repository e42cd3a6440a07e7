"""Build the native FMUs (docs/native.md).

For one model: instantiate its pythonfmu slave with its start values and initialise it (its
variables and the designs it computes), generate ``model_config.h`` and ``model_table.c``,
collect the C sources into ``sources/`` with ``buildDescription.xml`` and ``CMakeLists.txt``,
compile ``binaries/<platform>/<model>.so`` with the system C compiler and zip the FMU.  FMI
2.0 (``fmi2_native.c``) or, with ``fmi_version=3``, FMI 3.0 (``fmi3_native.c``, the
description by :mod:`fmus.native.fmi3xml`): the same core and adapters under either.
"""
from __future__ import annotations

import hashlib
import importlib
import json
import re
import shutil
import subprocess
import sys
import tempfile
import uuid
import zipfile
from pathlib import Path
from xml.etree import ElementTree as ET

import numpy as np

from fmus.export.mark import built_by_parcosim
from fmus.slave.base import START_VALUES_FILE
from fmus.slave.identity import IDENTITY_FILE
from fmus.export.modeldescription import model_structure
from fmus.slave.registry import SLAVES
from .fmi3xml import fmi3_model_description
from .models import NATIVE

HERE = Path(__file__).resolve().parent
KERNELS = HERE.parent.parent / "kernels" / "src"
#: The generic part every native FMU compiles (of no FMI version; :data:`LAYER` adds its FMI functions).
GENERIC = ("pcn_core.c", "pcn_values.c", "pcn_state.c", "pcn_text.c", "pcn_text.h", "pcn_model.h", "pcn_native.h")
#: The FMI layer of each FMI version (``--fmi-version``).
LAYER = {2: ("fmi2_native.c",), 3: ("fmi3_native.c", "fmi3_refused.c")}
#: As the kernels' library (kernels/build.py): no FMA contraction, so results match it bit for bit.
CFLAGS = ("-std=c11", "-O2", "-fPIC", "-fvisibility=hidden", "-ffp-contract=off", "-fno-fast-math")
#: What a sampled model adds (fmus/slave/sampling.py's sub-stepping): its generic part and the kernels' counting rule.
SAMPLED = ("pcn_sampling.c", "pcn_sampling.h")
SAMPLED_KERNELS = ("pc_sampling.c",)
DEFAULT_NATIVE_OUT = HERE.parent / "build" / "native"
_TYPE = {"Real": "PCN_REAL", "Integer": "PCN_INTEGER", "Boolean": "PCN_BOOLEAN", "String": "PCN_STRING"}
_CAUSALITY = {"input": "PCN_INPUT", "output": "PCN_OUTPUT", "parameter": "PCN_PARAMETER"}


class NativeBuildError(RuntimeError):
    """A native FMU could not be built (its slave does not initialise, no C compiler...)."""


def fmi_headers() -> Path:
    """The folder of the standard FMI 2.0 and 3.0 headers (fmpy ships them)."""
    import fmpy

    return Path(fmpy.__file__).resolve().parent / "c-code"


def platform_folder(fmi_version: int = 2) -> str:
    """The binaries folder of this machine: FMI 2.0's (linux64 ...) or FMI 3.0's (x86_64-linux ...)."""
    from fmpy import platform, platform_tuple

    return platform_tuple if fmi_version == 3 else platform


def _check_version(fmi_version: int) -> None:
    if fmi_version not in LAYER:
        raise ValueError(f"FMI version {fmi_version!r}: the native FMUs are FMI 2.0 or 3.0 (2 or 3)")


def initialised_slave(model: str, resources: Path):
    """The model's pythonfmu slave, initialised at t = 0 with its start values."""
    slave_class = getattr(importlib.import_module(f"fmus.slaves.{SLAVES[model]}"), model)
    slave = slave_class(instance_name=model, resources=str(resources))
    slave.setup_experiment(0.0)
    slave.enter_initialization_mode()
    slave.exit_initialization_mode()
    if slave.error:
        raise NativeBuildError(f"{model}: its slave does not initialise with its start values: {slave.error}")
    return slave


#: The slave's String output a native FMU does not have: the refusal's record (fmus/status.py),
#: which its C does not write (its refusals are the messages in ``error`` and the log).
NOT_NATIVE = "refusal"


def variables(slave) -> list[dict]:
    """The slave's variables in value-reference order (but :data:`NOT_NATIVE`, the last): name,
    vr, type, causality, tunable, start (its value before initialisation: the start value),
    description."""
    fresh = type(slave)(instance_name=slave.instance_name, resources=slave.resources)
    rows = []
    for vr in sorted(slave.vars):
        v = slave.vars[vr]
        if v.name == NOT_NATIVE:
            continue
        rows.append({"name": v.name, "vr": vr, "type": type(v).__name__, "causality": v.causality.name,
                     "tunable": v.variability is not None and v.variability.name == "tunable",
                     "start": getattr(fresh, v.name)})
    return rows


def _c_string(text: str) -> str:
    return json.dumps(text, ensure_ascii=True)   # a C string literal for ASCII text and \uXXXX-free names


def _c_double(x: float) -> str:
    if np.isfinite(x):
        return repr(float(x))
    return "(1.0 / 0.0)" if x > 0 else "(-1.0 / 0.0)" if x < 0 else "(0.0 / 0.0)"


def generate(model: str, rows: list[dict], scalars: dict, arrays: dict, guid: str) -> tuple[str, str]:
    """model_config.h and model_table.c of a native FMU."""
    slots = {t: 0 for t in _TYPE}
    header = [f"/* Generated by fmus/native/build.py for {model}: do not edit. */",
              "#ifndef PCN_MODEL_CONFIG_H", "#define PCN_MODEL_CONFIG_H", "",
              f"#define PCN_IDENTIFIER {_c_string(model)}"]
    table = [f"/* Generated by fmus/native/build.py for {model}: do not edit. */", '#include "model_config.h"',
             '#include "pcn_model.h"', "", f"const char pcn_guid[] = {_c_string(guid)};", "",
             "const pcn_variable pcn_variables[] = {"]
    for row in rows:
        kind = row["type"]
        slot = slots[kind]
        slots[kind] += 1
        if row["name"].isidentifier():      # a system's "ctrl.lam" has none: its adapter reads the table
            header.append(f"#define PCN_SLOT_{row['name']} {slot}   /* {kind} {row['causality']} */")
        start = row["start"]
        number = "0.0" if kind == "String" else _c_double(float(start))
        text = _c_string(start) if kind == "String" else "0"
        table.append(f"    {{{_c_string(row['name'])}, {row['vr']}u, {_TYPE[kind]}, {_CAUSALITY[row['causality']]}, "
                     f"{int(row['tunable'])}, {slot}, {number}, {text}}},")
    table += ["};", f"const int pcn_n_variables = {len(rows)};",
              "const int pcn_n_slots[4] = {" + ", ".join(str(slots[t]) for t in _TYPE) + "};", ""]
    header.append("")
    for name, value in scalars.items():
        literal = (_c_string(value) if isinstance(value, str) else str(value) if isinstance(value, int)
                   else _c_double(value))
        header.append(f"#define PCN_{name.upper()} {literal}")
    for name, array in arrays.items():
        if isinstance(array, (list, tuple)) and all(isinstance(x, str) for x in array):   # names
            header += [f"#define PCN_{name.upper()}_COUNT {len(array)}", f"extern const char *const pcn_{name}[];"]
            table += [f"const char *const pcn_{name}[] = {{{', '.join(map(_c_string, array))}}};", ""]
            continue
        flat = np.asarray(array, dtype=np.float64).ravel()
        header += [f"#define PCN_{name.upper()}_WORDS {flat.size}", f"extern const double pcn_{name}[];"]
        body = ",\n    ".join(", ".join(_c_double(x) for x in flat[k:k + 4]) for k in range(0, flat.size, 4))
        table += [f"const double pcn_{name}[] = {{\n    {body}\n}};", ""]
    header += ["", "#endif", ""]
    return "\n".join(header), "\n".join(table)


def kernel_files(kernels) -> list[Path]:
    """The kernels' C files and every header they include (transitively), from kernels/src."""
    found, todo = [], [KERNELS / name for name in kernels]
    while todo:
        path = todo.pop()
        if path in found:
            continue
        found.append(path)
        todo += [KERNELS / name for name in re.findall(r'#include "([^"]+)"', path.read_text())
                 if (KERNELS / name).exists()]
    return sorted(found)


def build_description(model: str, sources: list[str]) -> str:
    """sources/buildDescription.xml (FMI 3.0's, as FMI 2.0.4 recommends for source FMUs)."""
    root = ET.Element("fmiBuildDescription", fmiVersion="3.0")
    configuration = ET.SubElement(root, "BuildConfiguration", modelIdentifier=model)
    source_set = ET.SubElement(configuration, "SourceFileSet", language="C11")
    for name in sources:
        ET.SubElement(source_set, "SourceFile", name=name)
    ET.SubElement(configuration, "Library", name="m")
    ET.indent(root)
    return ET.tostring(root, encoding="unicode", xml_declaration=True) + "\n"


def cmake_lists(model: str, sources: list[str], fmi_version: int = 2) -> str:
    """sources/CMakeLists.txt: the FMU's shared library from these sources alone."""
    return (f"# Builds {model}'s binary from these sources; pass the FMI {fmi_version}.0 headers' folder:\n"
            f"#   cmake -DFMI_HEADERS=/path/to/headers -S . -B build && cmake --build build\n"
            "cmake_minimum_required(VERSION 3.10)\n"
            f"project({model} C)\n"
            "set(CMAKE_C_STANDARD 11)\n"
            f"add_library({model} SHARED {' '.join(sources)})\n"
            f"set_target_properties({model} PROPERTIES PREFIX \"\" C_VISIBILITY_PRESET hidden)\n"
            f"target_include_directories({model} PRIVATE . ${{FMI_HEADERS}})\n"
            f"if(NOT MSVC)\n  target_link_libraries({model} m)\nendif()\n")


def compile_command(sources_dir: Path, output: Path, compiler: str = "cc") -> list[str]:
    """The one command that compiles a native FMU's binary from its ``sources/`` folder."""
    files = sorted(str(p) for p in Path(sources_dir).glob("*.c"))
    return [compiler, *CFLAGS, "-shared", f"-I{sources_dir}", f"-I{fmi_headers()}", *files, "-o", str(output),
            "-Wl,--no-undefined", "-lm"]


def model_description(slave, model: str, guid: str, sources: list[str], feedthrough: dict,
                      fmi_version: int = 2, time_vr: int | None = None) -> bytes:
    """The native FMU's modelDescription.xml: the slave's (pythonfmu's writer), with its own
    GUID, no execution tool, the ModelStructure and the source files; FMI 3.0's has the same
    content (:func:`fmus.native.fmi3xml.fmi3_model_description`; its sources are in
    buildDescription.xml only) and the independent variable ``time`` at value reference
    ``time_vr``."""
    variable = "false" if getattr(type(slave), "has_sample_period", False) else "true"   # as fmus/export/build.py
    root = slave.to_xml({"canHandleVariableCommunicationStepSize": variable, "canGetAndSetFMUstate": "true",
                         "canSerializeFMUstate": "true", "needsExecutionTool": "false"})
    root.set("guid", guid)
    root.set("generationTool", "parcosim native (fmus/native)")
    listed = root.find("ModelVariables")
    for v in listed.findall("ScalarVariable"):
        if v.get("name") == NOT_NATIVE:       # the last: the other variables' indices stay
            listed.remove(v)
    if root.find("ModelStructure") is not None:
        root.remove(root.find("ModelStructure"))
    cosim = root.find("CoSimulation")
    files = ET.SubElement(cosim, "SourceFiles")
    for name in sources:
        if name.endswith(".c"):
            ET.SubElement(files, "File", name=name)
    root.append(model_structure(root, feedthrough))
    ET.indent(root)
    fmi2 = ET.tostring(root, encoding="UTF-8", xml_declaration=True)
    return fmi3_model_description(fmi2, time_vr) if fmi_version == 3 else fmi2


def build_native_fmu(model: str, out_dir=DEFAULT_NATIVE_OUT, compiler: str = "cc", start_values=None,
                     file_name=None, fmi_version: int = 2) -> Path:
    """Build ``<out_dir>/<file_name or model>.fmu``, the native FMU of ``model`` (FMI
    ``fmi_version``: 2 or 3), and return its path.  ``start_values`` (name -> value) replace
    the slave's start values: the FMU's defaults and the designs it carries are then theirs
    (an instance's parameters baked in)."""
    _check_version(fmi_version)
    if model not in NATIVE:
        raise ValueError(f"no native FMU of {model!r}; native: {', '.join(NATIVE)}")
    native = NATIVE[model]
    target = Path(out_dir) / f"{file_name or model}.fmu"
    if target.exists() and not built_by_parcosim(target, model):
        raise NativeBuildError(f"{target} was not built by parcosim: left alone")
    with tempfile.TemporaryDirectory(prefix="parcosim_native_") as tmp:
        tmp = Path(tmp)
        (tmp / "resources").mkdir()
        if start_values:
            (tmp / "resources" / START_VALUES_FILE).write_text(json.dumps(start_values))
        slave = initialised_slave(model, tmp / "resources")
        scalars, arrays = native.data(slave)
        generic = GENERIC + (SAMPLED if native.sampled else ())
        kernels = native.kernels + (SAMPLED_KERNELS if native.sampled else ())
        adapters = [HERE / "adapters" / name for name in (native.adapter, *native.parts)]
        files = [HERE / name for name in generic] + adapters + kernel_files(kernels)
        return package(model, slave, variables(slave), scalars, arrays, files, {}, target, compiler, fmi_version)


def package(model: str, slave, rows: list, scalars: dict, arrays: dict, files: list, generated: dict, target: Path,
            compiler: str = "cc", fmi_version: int = 2) -> Path:
    """Write the native FMU ``target`` of ``model``: ``files``, the FMI layer of
    ``fmi_version`` and the ``generated`` ones (name -> text) besides model_config.h and
    model_table.c (from ``rows``, ``scalars`` and ``arrays``, :func:`generate`) into
    ``sources/``, its binary compiled from them, the modelDescription.xml of ``slave`` (the
    pythonfmu slave, its declarations)."""
    _check_version(fmi_version)
    files = [*files, *(HERE / name for name in LAYER[fmi_version])]
    if len({f.name for f in files} | set(generated)) != len(files) + len(generated):   # sources/ is flat
        raise NativeBuildError(f"{model}: two source files share a name: {sorted(f.name for f in files)}")
    digest = hashlib.sha256(repr((model, rows, scalars, {k: np.asarray(v).tobytes() for k, v in arrays.items()},
                                  [f.read_bytes() for f in files], sorted(generated.items()))).encode()).hexdigest()
    guid = str(uuid.uuid5(uuid.NAMESPACE_URL, f"parcosim-native:{model}:{digest}"))
    time_vr = max(row["vr"] for row in rows) + 1   # FMI 3.0's independent variable "time"
    if fmi_version == 3:
        scalars = {**scalars, "time_vr": time_vr}
    config, table = generate(model, rows, scalars, arrays, guid)
    with tempfile.TemporaryDirectory(prefix="parcosim_native_fmu_") as tmp:
        fmu = Path(tmp)
        sources = fmu / "sources"
        sources.mkdir(parents=True)
        for f in files:
            shutil.copy2(f, sources / f.name)
        for name, text in {"model_config.h": config, "model_table.c": table, **generated}.items():
            (sources / name).write_text(text)
        names = sorted(p.name for p in sources.iterdir() if p.suffix == ".c")
        (sources / "buildDescription.xml").write_text(build_description(model, names))
        (sources / "CMakeLists.txt").write_text(cmake_lists(model, names, fmi_version))
        binary = fmu / "binaries" / platform_folder(fmi_version) / f"{model}.so"
        binary.parent.mkdir(parents=True)
        done = subprocess.run(compile_command(sources, binary, compiler), capture_output=True, text=True)
        if done.returncode != 0:
            raise NativeBuildError(f"{model}: compiling the native FMU failed:\n{done.stderr}")
        (fmu / "resources").mkdir()
        (fmu / "resources" / IDENTITY_FILE).write_text(json.dumps(
            {"model": model, "built_by": "parcosim", "native": True, "guid": guid, "model_identifier": model,
             "fmi_version": fmi_version}) + "\n")
        (fmu / "modelDescription.xml").write_bytes(model_description(
            slave, model, guid, names, getattr(type(slave), "feedthrough", {}), fmi_version, time_vr))
        target.parent.mkdir(parents=True, exist_ok=True)
        partial = target.parent / f".{target.name}.tmp"
        with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as z:
            for path in sorted(fmu.rglob("*")):
                if path.is_file():
                    z.write(path, path.relative_to(fmu).as_posix())
        partial.replace(target)
    return target


def source_digest() -> str:
    """SHA-256 of everything a native FMU is made from (C sources, kernels, generator, slaves)."""
    files = sorted([*HERE.rglob("*.c"), *HERE.rglob("*.h"), *HERE.glob("*.py"), *KERNELS.glob("*.[ch]"),
                    *(HERE.parent / "slaves").glob("*.py")])
    digest = hashlib.sha256()
    for path in files:
        digest.update(path.name.encode() + b"\0" + path.read_bytes())
    return digest.hexdigest()


def build_native_all(out_dir=DEFAULT_NATIVE_OUT, fmi_version: int = 2) -> list[Path]:
    """Build every native FMU (FMI ``fmi_version``: 2 or 3) into ``out_dir``; return their paths."""
    return [build_native_fmu(model, out_dir, fmi_version=fmi_version) for model in NATIVE]


if __name__ == "__main__":   # python -m fmus.native.build [OUT]
    for built in build_native_all(sys.argv[1] if len(sys.argv) > 1 else DEFAULT_NATIVE_OUT):
        print(built)
