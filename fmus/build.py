"""Build the parcosim FMUs with pythonfmu and fix their model descriptions.

Each FMU bundles the pure model packages (``plant``, ``motor``,
``controller``) and the slave base (:data:`BUNDLED_FMUS_MODULES`) in its resources, so
an importer needs only a Python 3.11 with numpy, scipy, numba and control.  Each FMU's
binary is parcosim's FMI wrapper (:mod:`fmus.wrapper`), compiled once per machine; without
a C compiler it stays pythonfmu's.
"""
from __future__ import annotations

import importlib
import shutil
import tempfile
import warnings
from pathlib import Path

from pythonfmu import FmuBuilder

from .foreign import built_by_parcosim, mark_file
from .modeldescription import fix_model_structure
from .registry import SLAVES
from .wrapper import SOURCE as WRAPPER_SOURCE
from .wrapper import install_wrapper

ROOT = Path(__file__).resolve().parent.parent
DEFAULT_OUT = ROOT / "fmus" / "build"
BUNDLED_PACKAGES = ("plant", "motor", "controller")
#: The modules of ``fmus`` the slaves import (the rest is the importer's side).
BUNDLED_FMUS_MODULES = ("guarded.py", "fmustate.py", "stateformat.py", "parts.py", "refusals.py", "budget.py")

#: Every parcosim FMU can save, restore and serialise its whole state (:mod:`fmus.fmustate`).
STATE_OPTIONS = {"canGetAndSetFMUstate": "true", "canSerializeFMUstate": "true"}


def stage_sources(tmp: Path, fmus_modules=BUNDLED_FMUS_MODULES, slaves: bool = False) -> list[Path]:
    """Copy the bundled sources (no caches) into tmp: the model packages, the ``fmus``
    modules named and, with ``slaves``, every slave module; return the project files."""
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc", "build")
    staged = []
    for package in BUNDLED_PACKAGES:
        if (ROOT / package).is_dir():
            shutil.copytree(ROOT / package, tmp / package, ignore=ignore)
            staged.append(tmp / package)
    fmus_pkg = tmp / "fmus"
    fmus_pkg.mkdir()
    (fmus_pkg / "__init__.py").write_text('"""The parcosim modules bundled into this FMU."""\n')
    for module in dict.fromkeys(BUNDLED_FMUS_MODULES + tuple(fmus_modules)):
        shutil.copy2(ROOT / "fmus" / module, fmus_pkg / module)
    if slaves:
        shutil.copytree(ROOT / "fmus" / "slaves", fmus_pkg / "slaves", ignore=ignore)
    staged.append(fmus_pkg)
    return staged


class ForeignFmuError(ValueError):
    """A file where parcosim would put one of its FMUs, that parcosim did not build."""


def build_fmu(model: str, out_dir: Path = DEFAULT_OUT) -> Path | None:
    """Build one FMU into out_dir and return its path.

    A file ``<model>.fmu`` already there that parcosim did not build (a foreign FMU,
    :func:`fmus.foreign.built_by_parcosim`) is left alone, with a warning: returns None.
    """
    if model not in SLAVES:
        raise ValueError(f"unknown FMU {model!r}; valid: {', '.join(SLAVES)}")
    out_dir = Path(out_dir)
    target = out_dir / f"{model}.fmu"
    if target.exists() and not built_by_parcosim(target, model):
        warnings.warn(f"{target} was not built by parcosim: left alone, not rebuilt (run a foreign FMU with "
                      "--replace INSTANCE=PATH)", stacklevel=2)
        return None
    out_dir.mkdir(parents=True, exist_ok=True)
    module_name = SLAVES[model]
    script = ROOT / "fmus" / "slaves" / f"{module_name}.py"
    slave_class = getattr(importlib.import_module(f"fmus.slaves.{module_name}"), model)
    with tempfile.TemporaryDirectory(prefix="parcosim_build_") as tmp:
        tmp = Path(tmp)
        project_files = stage_sources(tmp) + [mark_file(tmp, model)]
        staged_script = tmp / script.name
        shutil.copy2(script, staged_script)
        fmu = FmuBuilder.build_FMU(staged_script, dest=tmp / "out" / target.name, project_files=project_files,
                                   canHandleVariableCommunicationStepSize="true", **STATE_OPTIONS)
        fix_model_structure(fmu, getattr(slave_class, "feedthrough", {}))
        install_wrapper(fmu)
        shutil.move(fmu, target)
    return target


def _sources(model: str) -> list[Path]:
    files = [ROOT / "fmus" / module for module in BUNDLED_FMUS_MODULES] + [WRAPPER_SOURCE]
    files.append(ROOT / "fmus" / "slaves" / f"{SLAVES[model]}.py")
    for package in BUNDLED_PACKAGES:
        files.extend((ROOT / package).rglob("*.py"))
        files.extend((ROOT / package).rglob("*.csv"))
    return files


def ensure_built(models, out_dir=None) -> dict:
    """Model name -> FMU path in out_dir (default :data:`DEFAULT_OUT`), building each FMU
    that is missing or older than the sources it bundles.

    Raises
    ------
    ForeignFmuError
        ``<model>.fmu`` there was not built by parcosim: it is never loaded in place of ours
        (a foreign FMU runs as a component's FMU file, ``--replace INSTANCE=PATH``).
    FileNotFoundError
        A model that is not parcosim's, with no FMU file there.
    """
    out_dir = Path(out_dir) if out_dir is not None else DEFAULT_OUT
    paths = {}
    for model in models:
        path = out_dir / f"{model}.fmu"
        if model not in SLAVES:
            if not path.exists():
                raise FileNotFoundError(f"no FMU {path} and {model!r} is not a parcosim model")
        elif path.exists() and not built_by_parcosim(path, model):
            raise ForeignFmuError(f"{path} was not built by parcosim; to run it in place of {model}, use "
                                  "--replace INSTANCE=PATH (Component(model=PATH))")
        elif not path.exists() or path.stat().st_mtime < max(f.stat().st_mtime for f in _sources(model)):
            path = build_fmu(model, out_dir)
        paths[model] = path
    return paths


def build_all(out_dir: Path = DEFAULT_OUT) -> list[Path]:
    """Build every parcosim FMU into out_dir; foreign FMUs there are left alone (with a
    warning) and not listed."""
    return [path for path in (build_fmu(model, out_dir) for model in SLAVES) if path is not None]
