"""The mark of an FMU that ``parcosim build`` made: the build never overwrites a file without it
(an FMU of someone else's, :mod:`fmus.cosim.foreign`)."""
from __future__ import annotations

import json
import zipfile
from pathlib import Path

from fmus.slave.identity import IDENTITY_FILE

#: The file in an FMU's archive that says parcosim built it, and which model it is (the
#: FMU's identity, :mod:`fmus.slave.identity`).
MARK = f"resources/{IDENTITY_FILE}"
#: What every FMU parcosim built before the mark existed holds: the slave base.
_LEGACY = "resources/fmus/guarded.py"


def built_by_parcosim(path, model: str) -> bool:
    """True when ``path`` is an FMU that ``parcosim build`` made for ``model``: it carries
    the mark (or, built before the mark, the slave base and the model's name)."""
    try:
        with zipfile.ZipFile(path) as z:
            names = set(z.namelist())
            if MARK in names:
                return json.loads(z.read(MARK)).get("model") == model
            return _LEGACY in names and f'modelName="{model}"'.encode() in z.read("modelDescription.xml")
    except (KeyError, OSError, ValueError, zipfile.BadZipFile):
        return False


def mark_file(directory: Path, model: str, package: str) -> Path:
    """Write the mark for ``model``, whose code runs as the bundle ``package``
    (:mod:`fmus.export.bundle`), into ``directory`` (bundled as a resource by the build)."""
    path = Path(directory) / IDENTITY_FILE
    path.write_text(json.dumps({"model": model, "built_by": "parcosim", "package": package}) + "\n")
    return path
