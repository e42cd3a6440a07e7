"""Build the parcosim FMUs with pythonfmu and fix their model descriptions.

Each FMU bundles the pure model packages (``plant``, ``motor``, ``controller``), the C
kernels (``kernels``, the built library loaded by path) and the ``fmus`` modules its slaves
run on in its resources, under a private package name (:mod:`fmus.export.bundle`), and the designs
its initialisation computes with its parameters as built (:func:`precompute`,
:mod:`fmus.slave.designs`), so an importer needs a Python 3.11 with numpy and pythonfmu (and scipy
and python-control when a parameter set away from the build's asks for a new design), and its
own packages of those names are left alone.  Each FMU's
binary is parcosim's FMI wrapper (:mod:`fmus.export.wrapper`), compiled once per machine; without
a C compiler it stays pythonfmu's.
"""
from __future__ import annotations

import importlib
import shutil
import sys
import tempfile
import warnings
from pathlib import Path

from pythonfmu import FmuBuilder

from fmus.slave import designs
from fmus.export.archive import rewrite
from fmus.export.bundle import source_files, write_bundle
from fmus.export.mark import built_by_parcosim, mark_file
from fmus.export.modeldescription import fix_model_structure
from fmus.slave.registry import SLAVES
from fmus.export.wrapper import SOURCE as WRAPPER_SOURCE
from fmus.export.wrapper import install_wrapper

ROOT = Path(__file__).resolve().parents[2]
DEFAULT_OUT = ROOT / "fmus" / "build"

#: Every parcosim FMU can save, restore and serialise its whole state (:mod:`fmus.slave.state`).
STATE_OPTIONS = {"canGetAndSetFMUstate": "true", "canSerializeFMUstate": "true"}


def build_bundled_fmu(script, model: str, dest, resources=(), feedthrough=None, **options) -> Path:
    """Build the FMU of the slave module ``script`` (class ``model``) at ``dest`` (a ``.fmu``
    path) and return ``dest``.

    pythonfmu makes the model description and the archive; the resources then hold the
    bundle (:func:`fmus.export.bundle.write_bundle`, the slave module inside it, named dotted by
    ``slavemodule.txt``, and a copy as ``<that name>.py``, which pythonfmu's binary runs),
    the mark (:func:`fmus.export.mark.mark_file`), ``resources`` (files or folders) and, for a
    slave of ``fmus/slaves``, the designs its initialisation computes (:func:`precompute`); the
    ModelStructure is fixed (``feedthrough``: output -> inputs,
    :func:`fmus.export.modeldescription.fix_model_structure`) and parcosim's wrapper installed with
    the FMU's identity (:func:`fmus.export.wrapper.install_wrapper`).  ``options``: pythonfmu's
    model options (``canHandleVariableCommunicationStepSize`` ...).
    """
    script, dest = Path(script).resolve(), Path(dest)
    ours = script.parent == ROOT / "fmus" / "slaves"
    extra = () if ours else (script,)
    with tempfile.TemporaryDirectory(prefix="parcosim_build_") as tmp:
        tmp = Path(tmp)
        package = write_bundle(tmp / "bundle", extra)
        if ours:
            folder = tmp / "precompute"
            folder.mkdir()
            for item in map(Path, resources):
                (shutil.copytree if item.is_dir() else shutil.copy2)(item, folder / item.name)
            computed = precompute(script.stem, model, folder, tmp / designs.DESIGNS_FILE)
            resources = [*resources, *([computed] if computed else [])]
        staged = tmp / script.name
        shutil.copy2(script, staged)
        path_before = list(sys.path)
        try:
            with designs.isolated():    # pythonfmu instantiates the slave with the resources
                fmu = FmuBuilder.build_FMU(staged, dest=tmp / "out" / dest.name, **options, project_files=[
                    package, mark_file(tmp, model, package.name), *map(Path, resources)])
        finally:
            sys.path[:] = path_before   # pythonfmu leaves the script's folder on sys.path
        slave_module = f"{package.name}.fmus.slaves.{script.stem}"
        rewrite(fmu, fmu, {f"resources/{script.name}": None,   # the plain copy: the bundle has it
                           "resources/slavemodule.txt": slave_module,
                           # pythonfmu's binary (no C compiler) runs resources/<slavemodule.txt>.py
                           f"resources/{slave_module}.py": (package / "fmus" / "slaves" / script.name).read_bytes()})
        fix_model_structure(fmu, feedthrough or {})
        install_wrapper(fmu)
        dest.parent.mkdir(parents=True, exist_ok=True)
        shutil.move(fmu, dest)
    return dest


def precompute(module: str, model: str, resources: Path, path: Path) -> Path | None:
    """Write to ``path`` the designs file (:mod:`fmus.slave.designs`) of the FMU of slave ``module``
    (class ``model``) whose resources are the folder ``resources``: what its initialisation
    computes with its parameters as built (its start values, ``start_values.json`` if there),
    found by initialising it here; return ``path``, or None when it computes none.  An FMU
    whose initialisation fails here gets no file, with a warning (it then computes its designs
    when it starts, or refuses as it did here)."""
    slave_class = getattr(importlib.import_module(f"fmus.slaves.{module}"), model)
    with designs.recording() as recorded:
        slave = slave_class(instance_name=model, resources=str(resources))
        slave.setup_experiment(0.0)
        slave.enter_initialization_mode()
        slave.exit_initialization_mode()
        found = recorded()
    if slave.error:
        warnings.warn(f"{model}: its designs are not computed ahead, its initialisation here with its start values "
                      f"failed: {slave.error}", stacklevel=3)
        return None
    if not found:
        return None
    designs.write(found, path)
    return path


class ForeignFmuError(ValueError):
    """A file where parcosim would put one of its FMUs, that parcosim did not build."""


def build_fmu(model: str, out_dir: Path = DEFAULT_OUT) -> Path | None:
    """Build one FMU into out_dir and return its path.

    A file ``<model>.fmu`` already there that parcosim did not build (a foreign FMU,
    :func:`fmus.export.mark.built_by_parcosim`) is left alone, with a warning: returns None.
    """
    if model not in SLAVES:
        raise ValueError(f"unknown FMU {model!r}; valid: {', '.join(SLAVES)}")
    out_dir = Path(out_dir)
    target = out_dir / f"{model}.fmu"
    if target.exists() and not built_by_parcosim(target, model):
        warnings.warn(f"{target} was not built by parcosim: left alone, not rebuilt (run a foreign FMU with "
                      "--replace INSTANCE=PATH)", stacklevel=2)
        return None
    module_name = SLAVES[model]
    slave_class = getattr(importlib.import_module(f"fmus.slaves.{module_name}"), model)
    # A component with a sample period takes steps dividing it, changed only at a period's
    # start (fmus.slave.sampling): FMI's flag cannot say that, "false" is its safe side.
    variable = "false" if getattr(slave_class, "has_sample_period", False) else "true"
    return build_bundled_fmu(ROOT / "fmus" / "slaves" / f"{module_name}.py", model, target,
                             feedthrough=getattr(slave_class, "feedthrough", {}),
                             canHandleVariableCommunicationStepSize=variable, **STATE_OPTIONS)


def _sources() -> list[Path]:
    return [path for _, path in source_files()] + [WRAPPER_SOURCE, Path(__file__)]


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
        elif not path.exists() or path.stat().st_mtime < max(f.stat().st_mtime for f in _sources()):
            path = build_fmu(model, out_dir)
        paths[model] = path
    return paths


def build_all(out_dir: Path = DEFAULT_OUT) -> list[Path]:
    """Build every parcosim FMU into out_dir; foreign FMUs there are left alone (with a
    warning) and not listed."""
    return [path for path in (build_fmu(model, out_dir) for model in SLAVES) if path is not None]
