"""Build the test FMUs written in C (``dcdrive.c``, ``threshold.c``) with the system C
compiler and the FMI 2.0 headers that fmpy ships (``fmpy/c-code``)."""
from __future__ import annotations

import shutil
import subprocess
import zipfile
from pathlib import Path
from xml.etree import ElementTree as ET

HERE = Path(__file__).resolve().parent
#: FMU model name -> C source.
SOURCES = {"DCDrive": "dcdrive.c", "Threshold": "threshold.c"}


def compiler() -> str | None:
    """The C compiler on the PATH (cc or gcc), or None."""
    return shutil.which("cc") or shutil.which("gcc")


def fmi_headers() -> Path:
    import fmpy

    return Path(fmpy.__file__).resolve().parent / "c-code"


def build_c_fmu(model: str, out_dir) -> Path:
    """Compile ``model``'s source into ``<out_dir>/<model>.fmu`` (linux64) and return its path."""
    out_dir = Path(out_dir)
    xml = HERE / f"{model}.xml"
    identifier = ET.parse(xml).getroot().find("CoSimulation").get("modelIdentifier")
    library = out_dir / f"{identifier}.so"
    out_dir.mkdir(parents=True, exist_ok=True)
    subprocess.run([compiler(), "-shared", "-fPIC", "-O2", "-Wall", "-Werror", "-I", str(fmi_headers()),
                    "-I", str(HERE), "-o", str(library), str(HERE / SOURCES[model]), "-lm"],
                   check=True, capture_output=True, text=True)
    fmu = out_dir / f"{model}.fmu"
    with zipfile.ZipFile(fmu, "w", zipfile.ZIP_DEFLATED) as z:
        z.write(xml, "modelDescription.xml")
        z.write(library, f"binaries/linux64/{identifier}.so")
    return fmu
