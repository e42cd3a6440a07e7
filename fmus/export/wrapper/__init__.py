"""parcosim's FMI 2.0 export wrapper: compile it once per machine, put it into FMUs.

pythonfmu 0.7's compiled wrapper (the ``binaries/linux64/<modelIdentifier>.so`` of an FMU
it builds) crashes the importing process on hostile input and returns fmi2Fatal where
FMI 2.0 wants fmi2Error (issue 13, docs/extremes.md "The FMI wrapper").  Its PyPI
package ships no C++ source, so parcosim carries its own wrapper, ``parcosim_fmi2.c``: it
embeds the host's Python and drives the same pythonfmu slave classes and model
descriptions.

* :func:`compiled_wrapper` compiles it with the system C compiler (``cc`` or ``gcc``;
  ``$CC`` first) and caches the shared library by the hash of its source, the compiler
  flags and the Python it was compiled for;
* :func:`install_wrapper` replaces an FMU's Linux binary with it and writes the FMU's
  identity (GUID, modelIdentifier: :mod:`fmus.slave.identity`), which the wrapper checks at every
  instantiation.  Without a compiler the FMU keeps pythonfmu's binary, with one warning per
  process.

How the wrapper loads an FMU's bundled code: docs/bundle.md.
"""
from __future__ import annotations

import hashlib
import json
import os
import shlex
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import warnings
import zipfile
from pathlib import Path
from xml.etree import ElementTree as ET

from fmus.export.archive import rewrite
from fmus.slave.identity import IDENTITY_FILE

#: The wrapper's C source.
SOURCE = Path(__file__).resolve().parent / "parcosim_fmi2.c"
#: The symbol every parcosim wrapper exports (a function returning its version string).
VERSION_SYMBOL = "parcosimFmi2WrapperVersion"
#: Compiler flags beyond the include directory: Python's symbols are left to the host
#: process (the importer has libpython3.11 loaded), as pythonfmu's wrapper does.
CFLAGS = ("-O2", "-fPIC", "-shared", "-fvisibility=hidden", "-std=gnu11", "-pthread")
#: The platform folder of the binary inside an FMU.
PLATFORM = "linux64"

_warned = False


class WrapperBuildError(RuntimeError):
    """The compiler was found but failed on the wrapper (a bug to report, not a missing tool)."""


def compiler() -> str | None:
    """The C compiler: ``$CC`` if set and found, else ``cc`` or ``gcc`` on the PATH; None if none."""
    for candidate in (os.environ.get("CC"), "cc", "gcc"):
        if candidate:
            found = shutil.which(shlex.split(candidate)[0])
            if found:
                return found
    return None


def cache_dir() -> Path:
    """Where compiled wrappers are kept: ``$PARCOSIM_CACHE`` or ``$XDG_CACHE_HOME/parcosim``
    (default ``~/.cache/parcosim``), folder ``fmi2-wrapper``."""
    root = os.environ.get("PARCOSIM_CACHE") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache"), "parcosim")
    return Path(root) / "fmi2-wrapper"


def _include_dir() -> str:
    return sysconfig.get_paths()["include"]


def _key(cc: str) -> str:
    digest = hashlib.sha256(SOURCE.read_bytes())
    digest.update(repr((CFLAGS, _include_dir(), sys.version_info[:2], cc)).encode())
    return digest.hexdigest()[:16]


def compiled_wrapper(quiet: bool = False) -> Path | None:
    """The compiled wrapper (a shared library), compiled on first use and cached by the
    hash of its source, flags, compiler and Python.

    Returns None, with one warning per process (none with ``quiet``), if there is no C
    compiler or no ``Python.h``: the FMUs then keep pythonfmu's wrapper.

    Raises
    ------
    WrapperBuildError
        The compiler failed on the source (its output is in the message).
    """
    global _warned
    cc = compiler()
    include = _include_dir()
    reason = None
    if cc is None:
        reason = "no C compiler (cc or gcc) on the PATH"
    elif not os.path.isfile(os.path.join(include, "Python.h")):
        reason = f"no Python.h in {include} (install the Python development headers)"
    if reason is not None:
        if not (_warned or quiet):
            warnings.warn(f"parcosim's FMI wrapper not compiled: {reason}; the FMUs keep pythonfmu 0.7's wrapper, "
                          "which crashes the importer on some inputs (docs/extremes.md, 'The FMI wrapper')",
                          RuntimeWarning, stacklevel=2)
            _warned = True
        return None
    target = cache_dir() / f"parcosim_fmi2-{_key(cc)}.so"
    if target.is_file():
        return target
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=".parcosim_fmi2-", suffix=".so", dir=target.parent)
    os.close(fd)
    command = [cc, *CFLAGS, f"-I{include}", str(SOURCE), "-o", tmp]
    try:
        run = subprocess.run(command, capture_output=True, text=True)
        if run.returncode != 0:
            raise WrapperBuildError(f"compiling the FMI wrapper failed ({shlex.join(command)}):\n{run.stderr}")
        os.replace(tmp, target)   # atomic: a parallel build sees the old file or the whole new one
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
    return target


def model_identifier(fmu) -> str:
    """The co-simulation modelIdentifier of ``fmu`` (its binary's name)."""
    with zipfile.ZipFile(fmu) as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
    cs = root.find("CoSimulation")
    if cs is None or not cs.get("modelIdentifier"):
        raise ValueError(f"{fmu}: no co-simulation modelIdentifier in modelDescription.xml")
    return cs.get("modelIdentifier")


def identity(fmu) -> dict:
    """The identity ``fmu`` carries in ``resources/parcosim_build.json`` (:mod:`fmus.slave.identity`;
    {} if none) with the GUID and co-simulation modelIdentifier of its modelDescription.xml."""
    with zipfile.ZipFile(fmu) as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
        try:
            carried = json.loads(z.read(f"resources/{IDENTITY_FILE}"))
        except KeyError:
            carried = {}
    return {**carried, "guid": root.get("guid"), "model_identifier": model_identifier(fmu)}


def install_wrapper(fmu, quiet: bool = False) -> bool:
    """Replace ``fmu``'s ``binaries/linux64/<modelIdentifier>.so`` by parcosim's wrapper and
    write its identity (:func:`identity`), which the wrapper checks at instantiation, in
    place; return True if it did, False if no compiler is available (see
    :func:`compiled_wrapper`: the identity is written all the same, for the slave)."""
    fmu = Path(fmu)
    members = {f"resources/{IDENTITY_FILE}": json.dumps(identity(fmu)) + "\n"}
    wrapper = compiled_wrapper(quiet=quiet)
    if wrapper is not None:
        binary = f"binaries/{PLATFORM}/{model_identifier(fmu)}.so"
        info = zipfile.ZipInfo(binary, date_time=(2020, 1, 1, 0, 0, 0))
        info.external_attr = 0o755 << 16
        info.compress_type = zipfile.ZIP_DEFLATED
        members[binary] = (info, wrapper.read_bytes())
    rewrite(fmu, fmu, members)
    return wrapper is not None


def has_wrapper(fmu) -> bool:
    """Whether ``fmu``'s Linux binary is parcosim's wrapper (it exports :data:`VERSION_SYMBOL`)."""
    with zipfile.ZipFile(fmu) as z:
        binary = f"binaries/{PLATFORM}/{model_identifier(fmu)}.so"
        try:
            data = z.read(binary)
        except KeyError:
            return False
    return VERSION_SYMBOL.encode() in data
