"""Copy a zip archive (an FMU, an SSP package) with some members replaced or added.

The FMU build fixes the model description, installs the FMI wrapper and bakes start values;
the SSP tools rewrite a package's ``SystemStructure.ssd``: all of them copy an archive
member by member with a few members new.  :func:`rewrite` does that once, atomically.
"""
from __future__ import annotations

import os
import tempfile
import zipfile
from pathlib import Path


def umask_mode() -> int:
    """The mode ``open`` gives a new file under the process's umask (0o666 & ~umask): what
    a temporary file renamed into place is set to, since ``mkstemp`` makes it 0600.  Read from
    /proc where it can be (setting the umask to read it is process-wide, not thread-safe)."""
    try:
        with open("/proc/self/status", encoding="ascii") as status:
            mask = next(int(line.split()[1], 8) for line in status if line.startswith("Umask:"))
    except (OSError, StopIteration, ValueError, IndexError):
        mask = os.umask(0o022)
        os.umask(mask)
    return 0o666 & ~mask


def rewrite(source, target, members: dict) -> Path:
    """Write ``target`` as a copy of the zip ``source`` whose members ``members`` (name ->
    bytes or str, or name -> (ZipInfo, bytes) to set its attributes) replace or add to the
    old ones, a member named with None is left out; the others keep their entries.  ``target`` may be ``source``: it is replaced
    atomically (a temporary file in its folder, then renamed), as is any target."""
    source, target = Path(source), Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    os.close(fd)
    try:
        with zipfile.ZipFile(source) as src, zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as dst:
            for item in src.infolist():
                if item.filename not in members:
                    dst.writestr(item, src.read(item.filename))
            for name, data in members.items():
                if data is not None:
                    info, data = data if isinstance(data, tuple) else (name, data)
                    dst.writestr(info, data)
        os.chmod(tmp, umask_mode())
        os.replace(tmp, target)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
    return target
