"""parcosim's C kernels and their one binding layer (ctypes).

Each model's numerical step exists once, in C, in ``kernels/src/<model>.c`` (conventions in
``kernels/src/pc_common.h`` and docs/kernels.md).  :func:`library` loads the shared library
``kernels/libparcosim_kernels.so`` that ``pip install -e .`` builds (:mod:`kernels.build`);
the model modules (``plant``, ``motor``, ``controller``), the FMU slaves, the compiled mode
and the monolithic reference all call these functions, through ctypes, on numpy float64
buffers whose layout is the C structs' (:func:`layout`).

Inside an FMU the library travels in the bundle beside this file (``fmus/export/bundle.py``) and is
loaded by path: starting an FMU compiles nothing.  ``$PARCOSIM_KERNELS_LIB`` names another
build of the same sources to load instead (the sanitizer build of the tests).
"""
from __future__ import annotations

import ctypes
import functools
import operator
import os
import string
import weakref
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
LIBRARY = HERE / "libparcosim_kernels.so"
#: Environment variable naming a library to load instead of :data:`LIBRARY`.
LIBRARY_VARIABLE = "PARCOSIM_KERNELS_LIB"

c_double_p = ctypes.POINTER(ctypes.c_double)


class KernelsUnavailable(RuntimeError):
    """The C kernels cannot be loaded; the message says why and what to do."""


class Refusal(ctypes.Structure):
    """``pc_refusal``: the code of a refused step, which quantity (its index in the model's
    list) and the quantity's value."""

    _fields_ = [("code", ctypes.c_int), ("index", ctypes.c_int), ("value", ctypes.c_double)]


class Field(ctypes.Structure):
    """``pc_field``: one field of a struct of doubles (name, offset and count in doubles)."""

    _fields_ = [("name", ctypes.c_char_p), ("offset", ctypes.c_int), ("count", ctypes.c_int)]


_library = None


#: True inside an FMU: the package runs under its bundle's private name (fmus/export/bundle.py), with
#: the library built from its sources when the FMU was built (never stale, never built here).
BUNDLED = __name__ != "kernels"


def _folder() -> Path:
    """This package's folder.  In an FMU, the first one that still exists: the FMUs of one
    build share one bundle, which the FMI wrapper points at each one's extraction, dropping
    those an importer deleted (docs/bundle.md, "Loading")."""
    for entry in __path__:
        if os.path.isdir(entry):
            return Path(entry)
    return HERE


def _sources_present() -> bool:
    return any((HERE / "src").glob("*.c"))   # none when src is missing


def _load(path: Path) -> ctypes.CDLL:
    try:
        lib = ctypes.CDLL(str(path))
    except OSError as exc:
        raise KernelsUnavailable(f"parcosim's C kernels at {path} do not load: {exc}") from None
    lib.pc_sources_hash.restype = ctypes.c_char_p
    return lib


def library() -> ctypes.CDLL:
    """The kernels' shared library, loaded once per process.

    A missing or stale library (its sources changed since it was built) is built first when
    a C compiler is there.

    Raises
    ------
    KernelsUnavailable
        The library is missing or stale and cannot be built (no compiler: the message says
        what to install), or does not load.
    """
    global _library
    if _library is not None:
        return _library
    override = os.environ.get(LIBRARY_VARIABLE)
    if override:
        _library = _load(Path(override))
        return _library
    path = _folder() / LIBRARY.name
    if not BUNDLED and _sources_present():
        from . import build

        current = _load(path).pc_sources_hash().decode() if path.exists() else None
        if current != build.sources_hash():
            try:
                build.build(path)
            except build.NoCompiler as exc:
                state = "stale (its sources changed)" if path.exists() else "not built"
                raise KernelsUnavailable(f"parcosim's C kernels are {state} and cannot be built: {exc}") from None
            # a fresh path: dlopen would hand back the stale library already loaded
            _library = _load(_fresh_copy(path))
            return _library
    if not path.exists():
        raise KernelsUnavailable(f"parcosim's C kernels are missing: no {path} (reinstall parcosim with "
                                 "'pip install -e .', which builds them with the system C compiler)")
    _library = _load(path)
    return _library


def code_version() -> str:
    """The loaded library's hash of its sources and flags (``pc_sources_hash``): what a
    result computed by the kernels and kept on disk (a controller table) is keyed by, so a
    change of the C code is never answered from a cache it did not compute."""
    return library().pc_sources_hash().decode()


def _fresh_copy(path: Path) -> Path:
    """A copy of ``path`` under a name no process has loaded (the rebuilt library, when the
    stale one is already mapped), in a folder removed when the process exits."""
    import atexit
    import shutil
    import tempfile

    folder = Path(tempfile.mkdtemp(prefix="parcosim_kernels_"))
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    copy = folder / path.name
    shutil.copy2(path, copy)
    return copy


def function(name: str, restype, *argtypes):
    """The library's function ``name`` with its ctypes signature: a function object of its own
    (item access, not the library's cached attribute), so that no other declaration of the same
    symbol (a test's, another binding's) changes this one's argument types."""
    f = library()[name]
    f.restype, f.argtypes = restype, list(argtypes)
    return f


class _PerCall:
    def __repr__(self):
        return "kernels.PER_CALL"


#: In :func:`bind`'s arguments: the place of a value given at each call.
PER_CALL = _PerCall()


def bind(function, *arguments):
    """``function`` (of :func:`function`) with its fixed arguments converted once: the callable
    returned takes only the per-call values (the places given as :data:`PER_CALL`, in order)
    and returns the function's result.  The one way the model bindings cache their buffers'
    addresses (``plant.fast5r``, ``plant.wheeled_kernel``, ``motor.kernel``).

    A fixed argument is a numpy array (passed as its data address; the callable's ``buffers``
    keep it alive), a ctypes structure or array (its address), a ctypes scalar (passed as it is:
    its holder may change its value), None (NULL) or a number (converted to the argument type).
    The call passes ctypes objects to a copy of the function without argument types, so ctypes
    converts nothing (its cost grows with every argument it converts); a per-call value goes
    into a ctypes object of its argument type (TypeError: not a number of that type).  With no
    per-call value the callable is a ``functools.partial`` (no Python frame at all).

    The callable is code, not data, to an FMU state (:func:`fmus.slave.state.opaque_tag`); a copy
    of its owner binds its own (a deep copy of a function is the same function).
    """
    raw = library()[function.__name__]    # a new function object: ``function`` keeps its argtypes
    raw.restype = function.restype
    if len(arguments) != len(function.argtypes):
        raise TypeError(f"{function.__name__} takes {len(function.argtypes)} arguments, {len(arguments)} bound")
    args, slots, buffers = [], [], []
    for argtype, a in zip(function.argtypes, arguments):
        if a is PER_CALL:
            a = argtype()
            slots.append(a)
        elif isinstance(a, np.ndarray):
            buffers.append(a)
            a = ctypes.c_void_p(address(a))
        elif isinstance(a, (ctypes.Structure, ctypes.Array)):
            buffers.append(a)
            a = ctypes.c_void_p(ctypes.addressof(a))
        elif isinstance(a, (int, float)):
            a = argtype(a)
        args.append(a)
    call = functools.partial(raw, *args) if not slots else _setting(raw, args, tuple(slots))
    call.buffers = tuple(buffers)
    return call


_OWNED: dict = {}


def owned(owner, buffers: tuple, make):
    """``make(*buffers)`` (an owner's bound calls on its ``buffers``, e.g. of :func:`bind`) made
    once per ``owner`` and kept OUTSIDE it, made again when the owner holds other buffers
    (compared by identity; the entry keeps them).  An FMU state writes the owner's fields, so a
    stored address would be a forgeable pointer, and a deep copy's would name the original's
    arrays; kept here, neither can happen."""
    entry = _OWNED.get(id(owner))
    if entry is not None and all(map(operator.is_, entry[0], buffers)):
        return entry[1]
    if entry is None:
        weakref.finalize(owner, _OWNED.pop, id(owner), None)
    made = make(*buffers)
    _OWNED[id(owner)] = (tuple(buffers), made)
    return made


def _setting(raw, args, slots):
    """``raw(*args)`` after the per-call values go into ``slots`` (one to three set one by one:
    a loop costs about as much as the call)."""
    if len(slots) == 1:
        (a,) = slots

        def call(x):
            a.value = x
            return raw(*args)
    elif len(slots) == 2:
        a, b = slots

        def call(x, y):
            a.value, b.value = x, y
            return raw(*args)
    elif len(slots) == 3:
        a, b, c = slots

        def call(x, y, z):
            a.value, b.value, c.value = x, y, z
            return raw(*args)
    else:
        def call(*values):
            for slot, value in zip(slots, values):
                slot.value = value
            return raw(*args)
    return call


def layout(symbol: str) -> dict:
    """``{field: slice}`` of the struct whose ``pc_field`` list the library exports as
    ``symbol`` (terminated by a NULL name): its fields' places in a float64 buffer."""
    first = ctypes.cast(getattr(library(), symbol), ctypes.POINTER(Field))
    fields, k = {}, 0
    while first[k].name is not None:
        f = first[k]
        fields[f.name.decode()] = slice(f.offset, f.offset + f.count)
        k += 1
    return fields


def size(fields: dict) -> int:
    """The length in doubles of a struct whose :func:`layout` is ``fields``."""
    return max(s.stop for s in fields.values())


def address(array: np.ndarray) -> int:
    """The data address of a C-contiguous float64 (or int) array, for a ``c_void_p`` argument;
    the caller keeps ``array`` alive."""
    if not array.flags.c_contiguous:
        raise ValueError("a kernel buffer must be C-contiguous")
    return array.ctypes.data


# --- refusals: one record from the C code to the Python exception and the FMI message ----------

class Reason:
    """What a model's refusal code means: the quantities its ``pc_refusal.index`` picks from
    (``variables``), their unit, and the message template (``str.format`` fields
    ``variable``, ``value``, ``unit``, ``time`` and any given to :func:`refused`)."""

    __slots__ = ("name", "variables", "unit", "text", "fields")

    def __init__(self, name: str, variables: tuple, unit: str, text: str):
        self.name, self.variables, self.unit, self.text = name, tuple(variables), unit, text
        #: The template's field names (``time`` among them: its message names the time).
        self.fields = frozenset(f for _, f, _, _ in string.Formatter().parse(text) if f)


class Refused(ValueError):
    """A kernel's refusal as one record: ``instance`` (None until the FMI layer names it),
    ``time`` (s, or None outside a run), ``variable``, ``value``, ``unit``, ``code`` and
    ``reason`` (the model's code name), and the message (``str(exc)``), which names the
    variable, its value, its unit and, when ``names_time`` (:func:`timed`), the time."""

    def __init__(self, message: str, *, code: int, reason: str, variable: str, value: float, unit: str,
                 time: float | None = None, instance: str | None = None, names_time: bool = False):
        super().__init__(message)
        self.message, self.code, self.reason = message, code, reason
        self.variable, self.value, self.unit, self.time, self.instance = variable, value, unit, time, instance
        self.names_time = names_time

    def record(self) -> dict:
        """The record's fields as a dict (for logs, results and tests)."""
        return {"instance": self.instance, "time": self.time, "variable": self.variable, "value": self.value,
                "unit": self.unit, "code": self.code, "reason": self.reason, "message": self.message}


def refused(reasons: dict, refusal: Refusal, time: float | None = None, **fields) -> Refused:
    """The :class:`Refused` of a kernel's ``refusal`` under the model's ``reasons`` (code ->
    :class:`Reason`)."""
    reason = reasons[refusal.code]
    variable = reason.variables[refusal.index] if reason.variables else ""
    message = reason.text.format(variable=variable, value=refusal.value, unit=reason.unit, time=time, **fields)
    names_time = time is not None and "time" in reason.fields
    return Refused(message, code=refusal.code, reason=reason.name, variable=variable, value=refusal.value,
                   unit=reason.unit, time=time, names_time=names_time,
                   **{k: v for k, v in fields.items() if k == "instance"})


def timed(exc: BaseException) -> BaseException:
    """``exc``, marked as naming in its message the time of the step it refuses
    (``names_time``): the FMU slave that reports it adds no time of its own
    (:meth:`fmus.slave.base.GuardedSlave.do_step`).  A mark, so that nobody reads the message to
    find out."""
    exc.names_time = True
    return exc
