"""The model code an FMU carries, under a private package name.

Every parcosim FMU bundles the model packages (``plant``, ``motor``, ``controller``) and the
``fmus`` modules its slaves run on, in one package ``parcosim_<hash>`` in its resources
(:func:`write_bundle`).  Inside it every absolute import of those names is rewritten to the
private name (:func:`rewrite_imports`), so the bundled code never imports, nor adds to the
importer's ``sys.modules``, a ``plant``, ``motor``, ``controller`` or ``fmus`` of its own:
an importer's package of such a name is left alone, an installed parcosim does not stand
in for the bundle, and FMUs built from different sources run side by side in one process.

The hash covers every source file bundled (and this module, which decides the rewriting):
all the FMUs built from one checkout share one name, so in one process they share one copy
of the code and its compiled kernels; any change of a source gives a new name.  The
repository's own code keeps its plain imports; the few names it imports by string are
relative to its own package (:mod:`fmus.cosim.backends`, :mod:`fmus.cosim.compiled`).
"""
from __future__ import annotations

import ast
import hashlib
import re
import shutil
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
#: Model packages bundled whole.
PACKAGES = ("kernels", "plant", "motor", "controller")
#: The ``fmus`` modules bundled: the slave base, and the in-process master a system FMU
#: (``ClosedLoop``, ``ControlChain``) steps its components with; plus ``fmus/slaves``.
FMUS_MODULES = ("__init__.py", "status.py",
                "slave/__init__.py", "slave/base.py", "slave/state_calls.py", "slave/state.py", "slave/state_format.py",
                "slave/budget.py", "slave/declarations.py", "slave/refusals.py", "slave/identity.py",
                "slave/designs.py", "slave/registry.py", "slave/sampling.py",
                "cosim/__init__.py", "cosim/system.py", "cosim/master.py", "cosim/stepper.py", "cosim/backends.py",
                "cosim/foreign.py", "cosim/slots.py", "cosim/context.py", "cosim/compiled.py", "cosim/adapter.py",
                "cosim/compiled_adapters.py", "cosim/segments.py",
                "systemfmu/__init__.py", "systemfmu/cores.py", "systemfmu/slave_base.py")
#: Top-level names whose imports the bundle rewrites to its private package.
REWRITTEN = frozenset(PACKAGES + ("fmus",))
#: The private package's name: this prefix and 12 hex digits of the sources' hash.
PREFIX = "parcosim_"

_IGNORED = shutil.ignore_patterns("__pycache__", "*.pyc", "build", "*.tmp")


def source_files(extra=()) -> list:
    """(path in the bundle, file) of every file bundled, sorted by path in the bundle;
    ``extra``: slave modules from elsewhere (a benchmark's), bundled into ``fmus/slaves``."""
    files = [(f"fmus/slaves/{Path(p).name}", Path(p)) for p in extra]
    for package in PACKAGES:
        for path in (ROOT / package).rglob("*"):
            if path.is_file() and "__pycache__" not in path.parts and path.suffix not in (".pyc", ".tmp"):
                files.append((path.relative_to(ROOT).as_posix(), path))
    files += [(f"fmus/{name}", ROOT / "fmus" / name) for name in FMUS_MODULES]
    files += [(f"fmus/slaves/{p.name}", p) for p in (ROOT / "fmus" / "slaves").glob("*.py")]
    return sorted(files)


def bundle_name(extra=()) -> str:
    """``parcosim_<hash>``: the private package of the current sources and the ``extra``
    slave modules (see the module doc)."""
    digest = hashlib.sha256(Path(__file__).read_bytes())
    for relative, path in source_files(extra):
        digest.update(relative.encode() + b"\0" + hashlib.sha256(path.read_bytes()).digest())
    return PREFIX + digest.hexdigest()[:12]


def write_bundle(directory, extra=()) -> Path:
    """Write the bundle (package :func:`bundle_name`, imports rewritten; ``extra`` slave
    modules in ``fmus/slaves``; the C kernels' library built first if missing or stale) into
    ``directory`` and return the package's folder."""
    _build_kernels()
    name = bundle_name(extra)
    package = Path(directory) / name
    for relative, path in source_files(extra):
        target = package / relative
        target.parent.mkdir(parents=True, exist_ok=True)
        if path.suffix == ".py":
            target.write_bytes(rewrite_imports(path.read_bytes(), name, relative))
        else:
            shutil.copy2(path, target)
    (package / "__init__.py").write_text(f'"""parcosim\'s model code bundled into an FMU as {name} '
                                         '(fmus/export/bundle.py)."""\n')
    return package


def _build_kernels() -> None:
    """Build the C kernels' library now if it is missing or stale: the bundle carries it and
    the FMU loads it by path, so starting an FMU compiles nothing (issue 27, item 5).

    Raises
    ------
    kernels.KernelsUnavailable
        It cannot be built (no C compiler: the message says what to install).
    """
    import kernels

    kernels.library()
    if not kernels.LIBRARY.exists():     # $PARCOSIM_KERNELS_LIB named another build to load
        from kernels import build

        build.build()


def rewrite_imports(source: bytes, package: str, filename: str = "<bundled>") -> bytes:
    """``source`` with every absolute import of a :data:`REWRITTEN` name made an import of
    the same module inside ``package``; the names each statement binds are unchanged.

    ``from plant.x import y`` -> ``from P.plant.x import y``; ``import plant.x`` (binds
    ``plant``) -> ``import P.plant.x, P.plant as plant``; ``import plant.x as z`` ->
    ``import P.plant.x as z``; imports inside functions alike.  Only the module names are
    edited: line numbers, comments and layout stay.

    Raises
    ------
    SyntaxError
        ``source`` does not parse.
    """
    tree = ast.parse(source, filename)
    starts = _line_starts(source)
    edits = []   # (start, end, replacement) in bytes of source
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.level == 0 and _rewritten(node.module):
            start = starts[node.lineno - 1] + node.col_offset
            segment = source[start:starts[node.end_lineno - 1] + node.end_col_offset]
            found = re.match(rb"from(?:\s|\\\r?\n)+", segment)
            edits.append((start + found.end(), start + found.end(), f"{package}.".encode()))
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if _rewritten(alias.name):
                    start = starts[alias.lineno - 1] + alias.col_offset
                    end = starts[alias.end_lineno - 1] + alias.end_col_offset
                    edits.append((start, end, _import_alias(alias, package).encode()))
    for start, end, text in sorted(edits, reverse=True):
        source = source[:start] + text + source[end:]
    _check_rewritten(source, filename)
    return source


def _rewritten(module) -> bool:
    return bool(module) and module.split(".", 1)[0] in REWRITTEN


def _import_alias(alias: ast.alias, package: str) -> str:
    """One name of an ``import`` statement, rewritten so that it binds what it bound."""
    if alias.asname:
        return f"{package}.{alias.name} as {alias.asname}"
    top = alias.name.split(".", 1)[0]
    if alias.name == top:
        return f"{package}.{top} as {top}"
    return f"{package}.{alias.name}, {package}.{top} as {top}"   # binds `top` with `top.x` loaded


def _line_starts(source: bytes) -> list:
    """Byte offset of each line's start (ast's col_offset counts UTF-8 bytes)."""
    starts, offset = [], 0
    for line in source.splitlines(keepends=True):
        starts.append(offset)
        offset += len(line)
    return starts + [offset]


def _check_rewritten(source: bytes, filename: str) -> None:
    """Raise AssertionError if an absolute import of a :data:`REWRITTEN` name is left."""
    for node in ast.walk(ast.parse(source, filename)):
        names = [node.module] if isinstance(node, ast.ImportFrom) and node.level == 0 else \
            [a.name for a in node.names] if isinstance(node, ast.Import) else []
        left = [name for name in names if _rewritten(name)]
        if left:
            raise AssertionError(f"{filename}:{node.lineno}: import of {left} not rewritten")
